#pragma once
// Portable float maps (PFM): "PF" (3 channels, RGB) or "Pf" (1 channel), then
// "width height", then a scale whose sign gives the byte order (negative =
// little-endian), then raw float32 rows stored bottom-to-top.

#include <opencv2/core.hpp>

#include <filesystem>

namespace lightstage::io {

// Reads a PFM of either byte order into CV_32FC1 or CV_32FC3 (BGR in memory,
// like cv::imread), row 0 at the top. The scale's magnitude is ignored.
// Throws InputError naming the file for a missing, truncated or malformed file.
cv::Mat read_pfm(const std::filesystem::path& path);

// Writes CV_32FC1 or CV_32FC3 (BGR in memory) as a little-endian PFM,
// atomically. Throws InputError naming the file for other types.
void write_pfm(const std::filesystem::path& path, const cv::Mat& image);

}  // namespace lightstage::io
