#pragma once
// Object masks on disk: any 8/16-bit grey or RGB image; the object is where
// the mask equals its maximum (over all channels), as DiLiGenT defines it.

#include <opencv2/core.hpp>

#include <filesystem>

namespace lightstage::io {

// Reads a mask as CV_8UC1, 255 inside the object, 0 outside. Throws
// InputError naming the file when it is missing, not an image, or all zero.
cv::Mat read_mask(const std::filesystem::path& path);

}  // namespace lightstage::io
