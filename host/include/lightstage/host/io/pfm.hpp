#pragma once
// Portable float maps (PFM): "PF" (3 channels, RGB) or "Pf" (1 channel), then
// "width height", then a scale whose sign gives the byte order (negative =
// little-endian), then raw float32 rows stored bottom-to-top.

#include <opencv2/core.hpp>

#include <cstddef>
#include <filesystem>
#include <string_view>

namespace lightstage::io {

// What a PFM's header says.
struct PfmHeader {
  int width = 0;
  int height = 0;
  int channels = 0;  // 3 for "PF", 1 for "Pf"
  bool little_endian = true;
  std::size_t data_offset = 0;  // where the rows start
};

// Parses the header at the start of `bytes` (the file, or only its first
// bytes: the stack loader checks sizes before reading any pixel). Throws
// InputError naming `path` for a malformed or truncated header.
PfmHeader parse_pfm_header(const std::filesystem::path& path, std::string_view bytes);

// Reads a PFM of either byte order into CV_32FC1 or CV_32FC3 (BGR in memory,
// like cv::imread), row 0 at the top. The scale's magnitude is ignored.
// Throws InputError naming the file for a missing, truncated or malformed file.
cv::Mat read_pfm(const std::filesystem::path& path);

// Writes CV_32FC1 or CV_32FC3 (BGR in memory) as a little-endian PFM,
// atomically. Throws InputError naming the file for other types.
void write_pfm(const std::filesystem::path& path, const cv::Mat& image);

}  // namespace lightstage::io
