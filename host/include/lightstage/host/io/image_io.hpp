#pragma once
// Reading and writing images. In memory, 3-channel images are in OpenCV's BGR
// order (as cv::imread gives them); files on disk are whatever the format says
// (PNG and PFM both store RGB). Writes are atomic: a temporary file in the same
// folder, then a rename.

#include <opencv2/core.hpp>

#include <filesystem>

namespace lightstage::io {

// Reads an image as stored: CV_8U or CV_16U with 1 or 3 channels (an alpha
// channel is dropped, 2-channel grey+alpha keeps the grey), or CV_32FC1 /
// CV_32FC3 for .pfm files. By name: .pfm through pfm.hpp, .tif/.tiff through
// libtiff (tiff_image.hpp, float samples too), camera RAW files (.dng, .cr2,
// .nef, ...) decoded linear at half size (raw_image.hpp); anything else by
// its content through OpenCV. Throws InputError naming the file when it is
// missing, not an image, or of an unsupported depth.
cv::Mat read_image(const std::filesystem::path& path);

// Writes a PNG of the image's own depth: CV_8U or CV_16U, 1 or 3 (BGR)
// channels. Throws InputError naming the file for other types or write errors.
void write_png(const std::filesystem::path& path, const cv::Mat& image);

// Like write_png, but insists on a 16-bit image (CV_16UC1 or CV_16UC3).
void write_png16(const std::filesystem::path& path, const cv::Mat& image);

}  // namespace lightstage::io
