// Raw pixel unpacking: 16-bit little-endian Y10/Y12/Bayer, MIPI CSI-2 packed
// RAW10/RAW12, YUYV luma, strides and short buffers.
#include "lightstage/hw/pixel_formats.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

namespace lightstage::hw {
namespace {

TEST(PixelFormats, TableLooksUpByNameAndFourcc) {
  const PixelFormatDesc* y12 = find_pixel_format("Y12");
  ASSERT_NE(y12, nullptr);
  EXPECT_EQ(y12->bit_depth, 12);
  EXPECT_EQ(y12->packing, Packing::kLe16);
  EXPECT_EQ(find_v4l2_pixel_format(fourcc('B', 'A', '8', '1'))->name, "SBGGR8");
  EXPECT_EQ(find_v4l2_pixel_format(fourcc('B', 'A', '8', '1'))->cfa, camera::Cfa::kBGGR);
  EXPECT_EQ(find_pixel_format("SRGGB10P")->packing, Packing::kCsi2P10);
  EXPECT_EQ(find_pixel_format("MJPG"), nullptr);
  for (const auto& f : pixel_formats()) {
    EXPECT_EQ(find_pixel_format(f.name), &f) << f.name;
    EXPECT_EQ(find_v4l2_pixel_format(f.v4l2_fourcc), &f) << f.name;
  }
}

TEST(PixelFormats, Y10AndY12AreLowAlignedAndMasked) {
  // Two pixels per row, stride 6 (2 bytes of padding).
  const std::vector<std::uint8_t> data = {0xFF, 0x03, 0x01, 0x00, 0xAA, 0xAA,   // 1023, 1
                                          0x00, 0x02, 0xFF, 0xFF, 0xAA, 0xAA};  // 512, junk high bits
  const cv::Mat y10 = unpack_pixels(data, 2, 2, 6, Packing::kLe16, 10);
  ASSERT_EQ(y10.type(), CV_16UC1);
  EXPECT_EQ(y10.at<std::uint16_t>(0, 0), 1023);
  EXPECT_EQ(y10.at<std::uint16_t>(0, 1), 1);
  EXPECT_EQ(y10.at<std::uint16_t>(1, 0), 512);
  EXPECT_EQ(y10.at<std::uint16_t>(1, 1), 1023);  // 0xFFFF masked to 10 bits
  const cv::Mat y12 = unpack_pixels(data, 2, 2, 6, Packing::kLe16, 12);
  EXPECT_EQ(y12.at<std::uint16_t>(1, 1), 4095);
  const cv::Mat y16 = unpack_pixels(data, 2, 2, 6, Packing::kLe16, 16);
  EXPECT_EQ(y16.at<std::uint16_t>(1, 1), 65535);
}

TEST(PixelFormats, Csi2Raw10PacksFourPixelsInFiveBytes) {
  // Pixels 0x3FF, 0x001, 0x200, 0x155: high bytes FF 00 80 55, low bits 11 01 00 01.
  const std::vector<std::uint8_t> data = {0xFF, 0x00, 0x80, 0x55, 0b01'00'01'11};
  const cv::Mat m = unpack_pixels(data, 4, 1, 5, Packing::kCsi2P10, 10);
  EXPECT_EQ(m.at<std::uint16_t>(0, 0), 0x3FF);
  EXPECT_EQ(m.at<std::uint16_t>(0, 1), 0x001);
  EXPECT_EQ(m.at<std::uint16_t>(0, 2), 0x200);
  EXPECT_EQ(m.at<std::uint16_t>(0, 3), 0x155);
  EXPECT_EQ(min_row_bytes(Packing::kCsi2P10, 4), 5u);
  EXPECT_EQ(min_row_bytes(Packing::kCsi2P10, 6), 8u);
}

TEST(PixelFormats, Csi2Raw12PacksTwoPixelsInThreeBytes) {
  // Pixels 0xABC, 0x123: high bytes AB 12, low nibbles C and 3 -> 0x3C.
  const std::vector<std::uint8_t> data = {0xAB, 0x12, 0x3C, 0xFF, 0x00, 0x0F};
  const cv::Mat m = unpack_pixels(data, 4, 1, 6, Packing::kCsi2P12, 12);
  EXPECT_EQ(m.at<std::uint16_t>(0, 0), 0xABC);
  EXPECT_EQ(m.at<std::uint16_t>(0, 1), 0x123);
  EXPECT_EQ(m.at<std::uint16_t>(0, 2), 0xFFF);
  EXPECT_EQ(m.at<std::uint16_t>(0, 3), 0x000);
}

TEST(PixelFormats, EightBitBayerAndYuyv) {
  const std::vector<std::uint8_t> bayer = {1, 2, 3, 9, 4, 5, 6, 9};  // stride 4, width 3
  const cv::Mat b = unpack_pixels(bayer, 3, 2, 4, Packing::kBytes8, 8);
  ASSERT_EQ(b.type(), CV_8UC1);
  EXPECT_EQ(b.at<std::uint8_t>(1, 2), 6);
  const std::vector<std::uint8_t> yuyv = {10, 128, 20, 129, 30, 128, 40, 129};
  const cv::Mat y = unpack_pixels(yuyv, 4, 1, 8, Packing::kYuyvLuma, 8);
  EXPECT_EQ(y.at<std::uint8_t>(0, 0), 10);
  EXPECT_EQ(y.at<std::uint8_t>(0, 3), 40);
}

TEST(PixelFormats, ShortBuffersAndStridesAreRefused) {
  const std::vector<std::uint8_t> data(10);
  EXPECT_THROW(unpack_pixels(data, 4, 2, 8, Packing::kLe16, 12), std::invalid_argument);  // needs 16
  EXPECT_THROW(unpack_pixels(data, 4, 1, 4, Packing::kLe16, 12), std::invalid_argument);  // stride < 8
  EXPECT_THROW(unpack_pixels(data, 0, 1, 4, Packing::kBytes8, 8), std::invalid_argument);
  EXPECT_NO_THROW(unpack_pixels(data, 4, 1, 8, Packing::kLe16, 12));  // the last row needs no padding
}

}  // namespace
}  // namespace lightstage::hw
