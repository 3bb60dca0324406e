#pragma once
// The pixel formats the camera backends deliver, under one set of names
// (V4L2's), and the code that turns a driver's buffer into a cv::Mat: 8-bit
// formats as CV_8UC1, deeper ones as CV_16UC1 holding the sensor's values
// (not scaled), Bayer kept mosaicked, YUYV reduced to its luma.

#include "lightstage/common/camera.hpp"

#include <opencv2/core/mat.hpp>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

namespace lightstage::hw {

// How pixels sit in the buffer.
enum class Packing {
  kBytes8,    // one byte per pixel
  kLe16,      // little-endian 16-bit words, value in the low bit_depth bits (Y10, Y12, SRGGB12, ...)
  kCsi2P10,   // MIPI CSI-2 RAW10: 4 pixels in 5 bytes (4 high bytes, then the 2-bit remainders)
  kCsi2P12,   // MIPI CSI-2 RAW12: 2 pixels in 3 bytes (2 high bytes, then the 4-bit remainders)
  kYuyvLuma,  // YUYV 4:2:2; the Y samples become a grey image
};

constexpr std::uint32_t fourcc(char a, char b, char c, char d) {
  return static_cast<std::uint32_t>(static_cast<unsigned char>(a)) |
         static_cast<std::uint32_t>(static_cast<unsigned char>(b)) << 8 |
         static_cast<std::uint32_t>(static_cast<unsigned char>(c)) << 16 |
         static_cast<std::uint32_t>(static_cast<unsigned char>(d)) << 24;
}

struct PixelFormatDesc {
  std::string_view name;      // "SRGGB12"
  std::uint32_t v4l2_fourcc;  // V4L2_PIX_FMT_SRGGB12
  int bit_depth;
  camera::Cfa cfa;
  Packing packing;
};

// Every format the backends can unpack.
std::span<const PixelFormatDesc> pixel_formats();
const PixelFormatDesc* find_pixel_format(std::string_view name);
const PixelFormatDesc* find_v4l2_pixel_format(std::uint32_t v4l2_fourcc);

// The smallest number of bytes one row of `width` pixels takes.
std::size_t min_row_bytes(Packing packing, int width);

// Turns `height` rows of `stride` bytes each into an image of width x height
// (CV_8UC1 for 8-bit formats, CV_16UC1 otherwise). Values deeper than
// bit_depth are masked off. Throws std::invalid_argument when `data` is too
// short or the stride too small for the width.
cv::Mat unpack_pixels(std::span<const std::uint8_t> data, int width, int height, std::size_t stride,
                      Packing packing, int bit_depth);

}  // namespace lightstage::hw
