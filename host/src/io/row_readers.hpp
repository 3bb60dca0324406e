#pragma once
// The row readers behind open_row_reader (lightstage/host/io/row_reader.hpp), one per format.

#include "lightstage/host/io/row_reader.hpp"

#include <filesystem>
#include <memory>

namespace lightstage::io {

// libpng; nullptr for an interlaced PNG (its rows come out only at the last pass).
std::unique_ptr<RowReader> open_png_rows(const std::filesystem::path& path);
// libtiff strips or tiles.
std::unique_ptr<RowReader> open_tiff_rows(const std::filesystem::path& path);

}  // namespace lightstage::io
