#include "lightstage/hw/pixel_formats.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <stdexcept>

namespace lightstage::hw {

namespace {

using camera::Cfa;

constexpr std::array kFormats = {
    PixelFormatDesc{"GREY", fourcc('G', 'R', 'E', 'Y'), 8, Cfa::kNone, Packing::kBytes8},
    PixelFormatDesc{"Y10", fourcc('Y', '1', '0', ' '), 10, Cfa::kNone, Packing::kLe16},
    PixelFormatDesc{"Y12", fourcc('Y', '1', '2', ' '), 12, Cfa::kNone, Packing::kLe16},
    PixelFormatDesc{"Y16", fourcc('Y', '1', '6', ' '), 16, Cfa::kNone, Packing::kLe16},
    PixelFormatDesc{"Y10P", fourcc('Y', '1', '0', 'P'), 10, Cfa::kNone, Packing::kCsi2P10},
    PixelFormatDesc{"YUYV", fourcc('Y', 'U', 'Y', 'V'), 8, Cfa::kNone, Packing::kYuyvLuma},
    PixelFormatDesc{"SBGGR8", fourcc('B', 'A', '8', '1'), 8, Cfa::kBGGR, Packing::kBytes8},
    PixelFormatDesc{"SGBRG8", fourcc('G', 'B', 'R', 'G'), 8, Cfa::kGBRG, Packing::kBytes8},
    PixelFormatDesc{"SGRBG8", fourcc('G', 'R', 'B', 'G'), 8, Cfa::kGRBG, Packing::kBytes8},
    PixelFormatDesc{"SRGGB8", fourcc('R', 'G', 'G', 'B'), 8, Cfa::kRGGB, Packing::kBytes8},
    PixelFormatDesc{"SBGGR10", fourcc('B', 'G', '1', '0'), 10, Cfa::kBGGR, Packing::kLe16},
    PixelFormatDesc{"SGBRG10", fourcc('G', 'B', '1', '0'), 10, Cfa::kGBRG, Packing::kLe16},
    PixelFormatDesc{"SGRBG10", fourcc('B', 'A', '1', '0'), 10, Cfa::kGRBG, Packing::kLe16},
    PixelFormatDesc{"SRGGB10", fourcc('R', 'G', '1', '0'), 10, Cfa::kRGGB, Packing::kLe16},
    PixelFormatDesc{"SBGGR12", fourcc('B', 'G', '1', '2'), 12, Cfa::kBGGR, Packing::kLe16},
    PixelFormatDesc{"SGBRG12", fourcc('G', 'B', '1', '2'), 12, Cfa::kGBRG, Packing::kLe16},
    PixelFormatDesc{"SGRBG12", fourcc('B', 'A', '1', '2'), 12, Cfa::kGRBG, Packing::kLe16},
    PixelFormatDesc{"SRGGB12", fourcc('R', 'G', '1', '2'), 12, Cfa::kRGGB, Packing::kLe16},
    PixelFormatDesc{"SBGGR16", fourcc('B', 'Y', 'R', '2'), 16, Cfa::kBGGR, Packing::kLe16},
    PixelFormatDesc{"SGBRG16", fourcc('G', 'B', '1', '6'), 16, Cfa::kGBRG, Packing::kLe16},
    PixelFormatDesc{"SGRBG16", fourcc('G', 'R', '1', '6'), 16, Cfa::kGRBG, Packing::kLe16},
    PixelFormatDesc{"SRGGB16", fourcc('R', 'G', '1', '6'), 16, Cfa::kRGGB, Packing::kLe16},
    PixelFormatDesc{"SBGGR10P", fourcc('p', 'B', 'A', 'A'), 10, Cfa::kBGGR, Packing::kCsi2P10},
    PixelFormatDesc{"SGBRG10P", fourcc('p', 'G', 'A', 'A'), 10, Cfa::kGBRG, Packing::kCsi2P10},
    PixelFormatDesc{"SGRBG10P", fourcc('p', 'g', 'A', 'A'), 10, Cfa::kGRBG, Packing::kCsi2P10},
    PixelFormatDesc{"SRGGB10P", fourcc('p', 'R', 'A', 'A'), 10, Cfa::kRGGB, Packing::kCsi2P10},
    PixelFormatDesc{"SBGGR12P", fourcc('p', 'B', 'C', 'C'), 12, Cfa::kBGGR, Packing::kCsi2P12},
    PixelFormatDesc{"SGBRG12P", fourcc('p', 'G', 'C', 'C'), 12, Cfa::kGBRG, Packing::kCsi2P12},
    PixelFormatDesc{"SGRBG12P", fourcc('p', 'g', 'C', 'C'), 12, Cfa::kGRBG, Packing::kCsi2P12},
    PixelFormatDesc{"SRGGB12P", fourcc('p', 'R', 'C', 'C'), 12, Cfa::kRGGB, Packing::kCsi2P12},
};

}  // namespace

std::span<const PixelFormatDesc> pixel_formats() { return kFormats; }

const PixelFormatDesc* find_pixel_format(std::string_view name) {
  for (const auto& f : kFormats) {
    if (f.name == name) return &f;
  }
  return nullptr;
}

const PixelFormatDesc* find_v4l2_pixel_format(std::uint32_t v4l2_fourcc) {
  for (const auto& f : kFormats) {
    if (f.v4l2_fourcc == v4l2_fourcc) return &f;
  }
  return nullptr;
}

std::size_t min_row_bytes(Packing packing, int width) {
  const auto w = static_cast<std::size_t>(width);
  switch (packing) {
    case Packing::kBytes8:
      return w;
    case Packing::kLe16:
      return 2 * w;
    case Packing::kCsi2P10:
      return (w * 5 + 3) / 4;
    case Packing::kCsi2P12:
      return (w * 3 + 1) / 2;
    case Packing::kYuyvLuma:
      return 2 * w;
  }
  return 0;
}

cv::Mat unpack_pixels(std::span<const std::uint8_t> data, int width, int height, std::size_t stride,
                      Packing packing, int bit_depth) {
  if (width <= 0 || height <= 0)
    throw std::invalid_argument(fmt::format("bad image size {}x{}", width, height));
  const std::size_t row_bytes = min_row_bytes(packing, width);
  if (stride < row_bytes) {
    throw std::invalid_argument(fmt::format("stride {} is less than the {} bytes a row of {} pixels needs",
                                            stride, row_bytes, width));
  }
  const std::size_t needed = stride * static_cast<std::size_t>(height - 1) + row_bytes;
  if (data.size() < needed) {
    throw std::invalid_argument(fmt::format("buffer holds {} bytes, a {}x{} image with stride {} needs {}",
                                            data.size(), width, height, stride, needed));
  }
  const bool eight_bit = packing == Packing::kBytes8 || packing == Packing::kYuyvLuma;
  cv::Mat image(height, width, eight_bit ? CV_8UC1 : CV_16UC1);
  const std::uint16_t mask =
      bit_depth >= 16 ? std::uint16_t{0xffff} : static_cast<std::uint16_t>((1u << bit_depth) - 1);
  for (int y = 0; y < height; ++y) {
    const std::uint8_t* in = data.data() + stride * static_cast<std::size_t>(y);
    switch (packing) {
      case Packing::kBytes8: {
        std::copy(in, in + width, image.ptr<std::uint8_t>(y));
        break;
      }
      case Packing::kYuyvLuma: {
        auto* out = image.ptr<std::uint8_t>(y);
        for (int x = 0; x < width; ++x) out[x] = in[2 * x];
        break;
      }
      case Packing::kLe16: {
        auto* out = image.ptr<std::uint16_t>(y);
        for (int x = 0; x < width; ++x) {
          out[x] = static_cast<std::uint16_t>((in[2 * x] | in[2 * x + 1] << 8) & mask);
        }
        break;
      }
      case Packing::kCsi2P10: {
        auto* out = image.ptr<std::uint16_t>(y);
        for (int x = 0; x < width; ++x) {
          const std::uint8_t* group = in + (x / 4) * 5;
          const int i = x % 4;
          out[x] = static_cast<std::uint16_t>(group[i] << 2 | ((group[4] >> (2 * i)) & 0x3));
        }
        break;
      }
      case Packing::kCsi2P12: {
        auto* out = image.ptr<std::uint16_t>(y);
        for (int x = 0; x < width; ++x) {
          const std::uint8_t* group = in + (x / 2) * 3;
          const int i = x % 2;
          out[x] = static_cast<std::uint16_t>(group[i] << 4 | ((group[2] >> (4 * i)) & 0xf));
        }
        break;
      }
    }
  }
  return image;
}

}  // namespace lightstage::hw
