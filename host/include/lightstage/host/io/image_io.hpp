#pragma once
// Reading and writing images. In memory, 3-channel images are in OpenCV's BGR
// order (as cv::imread gives them; we decode without it, see
// cmake/LightstageDependencies.cmake); files on disk are whatever the format says
// (PNG and PFM both store RGB). Writes are atomic: a temporary file in the same
// folder, then a rename.

#include <opencv2/core.hpp>

#include <filesystem>
#include <string>
#include <string_view>

namespace lightstage::io {

// Reads an image as stored: CV_8U or CV_16U with 1 or 3 channels (alpha is
// dropped: grey with alpha becomes BGR), or CV_32FC1 / CV_32FC3 for .pfm files.
// By name: .pfm through pfm.hpp, .tif/.tiff through libtiff (tiff_image.hpp,
// float samples too), camera RAW files (.dng, .cr2, .nef, ...) decoded linear
// at half size (raw_image.hpp); by content: PNG through libpng, JPEG through
// libjpeg (jpeg_image.hpp, no EXIF rotation). Throws InputError naming the
// file when it is missing, none of those, or cannot be decoded.
cv::Mat read_image(const std::filesystem::path& path);

// Writes a PNG of the image's own depth: CV_8U or CV_16U, 1 or 3 (BGR)
// channels. Throws InputError naming the file for other types or write errors.
void write_png(const std::filesystem::path& path, const cv::Mat& image);

// The PNG write_png would write, in memory (`name` goes into errors); also
// 4 channels (BGRA, written RGBA).
std::string encode_png(const cv::Mat& image, std::string_view name = "PNG");

// Like write_png, but insists on a 16-bit image (CV_16UC1 or CV_16UC3).
void write_png16(const std::filesystem::path& path, const cv::Mat& image);

}  // namespace lightstage::io
