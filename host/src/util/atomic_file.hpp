#pragma once
// Writing files so that a reader never sees half of one: write to a temporary
// name in the same folder (same extension, so format-by-extension writers such
// as cv::imwrite still work), then rename over the target.

#include <filesystem>
#include <string>

namespace lightstage::util {

// A fresh, unused name beside `target` ending in target's extension,
// e.g. "dir/.normal.png.tmp-1234-7.png".
std::filesystem::path temporary_sibling(const std::filesystem::path& target);

// Renames `temporary` to `target`; on failure removes `temporary` and throws
// InputError naming `target`.
void commit_temporary(const std::filesystem::path& temporary, const std::filesystem::path& target);

// Writes `text` to `path` atomically; throws InputError naming `path`.
void write_text_atomic(const std::filesystem::path& path, const std::string& text);

}  // namespace lightstage::util
