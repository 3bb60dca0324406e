#pragma once
// JPEG files through libjpeg(-turbo): camera JPEGs read as stored (8-bit grey
// or BGR, no EXIF rotation: io/exif.hpp has the orientation), and 8-bit images
// encoded with libjpeg's defaults (4:2:0 chroma, baseline) at a given quality.

#include <opencv2/core.hpp>

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>

namespace lightstage::io {

// By content: the JPEG start-of-image marker (FF D8 FF), whatever the name.
bool is_jpeg_file(const std::filesystem::path& path);

// CV_8UC1 for a one-component JPEG, CV_8UC3 (BGR) for YCbCr or RGB ones.
// Throws InputError naming the file (or `name`, for bytes in memory) when it
// cannot be opened or decoded, is CMYK, or is larger than kMaxImageSide on a
// side (io/stack_io.hpp).
cv::Mat read_jpeg(const std::filesystem::path& path);
cv::Mat decode_jpeg(std::span<const std::uint8_t> bytes, std::string_view name);
// The size its header declares, nothing decoded; throws as read_jpeg.
cv::Size read_jpeg_size(const std::filesystem::path& path);

// The JPEG file's bytes. `image`: CV_8UC1 or CV_8UC3 (BGR); `quality` 1 to 100. Throws InputError
// naming `name` for another type or quality.
std::string encode_jpeg(const cv::Mat& image, int quality, std::string_view name = "JPEG");
// encode_jpeg into `path`, atomically (a temporary sibling, then a rename).
void write_jpeg(const std::filesystem::path& path, const cv::Mat& image, int quality);

}  // namespace lightstage::io
