#pragma once
// Where a downloaded shot lands: a new file in the download folder under the
// camera's own name, never over an existing file, and never seen half
// written (written under a temporary name beside it, then renamed).

#include <filesystem>
#include <functional>
#include <string>
#include <string_view>

namespace lightstage::hw {

// Throws camera::CameraError naming `uri` and the folder unless `dir` is an
// existing folder this process can write into.
void check_download_dir(const std::filesystem::path& dir, const std::string& uri);

// Creates a file in `dir` with what `write` writes into the open descriptor
// it is given (it must not close it), and returns its path: `name` (its last
// component only), or "STEM-1.EXT", "STEM-2.EXT", ... when that is taken.
// Throws camera::CameraError naming `uri` and the path when the file cannot
// be written; whatever `write` throws goes through. Either way nothing is
// left behind.
std::filesystem::path write_new_file(const std::filesystem::path& dir, std::string_view name,
                                     const std::string& uri, const std::function<void(int fd)>& write);

}  // namespace lightstage::hw
