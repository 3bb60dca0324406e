#pragma once
// The name a file is written under before it is renamed over its target, so
// that a reader never sees half of it (host/src/util/atomic_file.hpp,
// sim/dng_writer.hpp).

#include <filesystem>

namespace lightstage {

// A fresh, unused name beside `target` ending in target's extension (so that
// format-by-extension writers such as cv::imwrite still work), hidden, with the
// process id and a counter: e.g. "dir/.normal.png.tmp-1234-7.png".
std::filesystem::path temporary_sibling(const std::filesystem::path& target);

}  // namespace lightstage
