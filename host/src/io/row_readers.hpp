#pragma once
// The row readers behind open_row_reader (lightstage/host/io/row_reader.hpp), one per format.

#include "lightstage/host/io/row_reader.hpp"

#include <filesystem>
#include <memory>

namespace lightstage::io {

// libpng; nullptr for an interlaced PNG (its rows come out only at the last pass).
std::unique_ptr<RowReader> open_png_rows(const std::filesystem::path& path);
// libpng, every row at once (interlaced too), as open_png_rows transforms them. Throws InputError naming the
// file.
cv::Mat read_png(const std::filesystem::path& path);
// libtiff strips or tiles.
std::unique_ptr<RowReader> open_tiff_rows(const std::filesystem::path& path);
// A file that decodes only whole (camera RAW, interlaced PNG), decoded into
// `image`: its rows go to an unlinked file in the temporary folder ($TMPDIR)
// and are read back a band at a time, so a stack of such files holds one
// decoded frame per reader being opened, not one per frame.
std::unique_ptr<RowReader> spill_decoded_rows(const std::filesystem::path& path, const cv::Mat& image);

}  // namespace lightstage::io
