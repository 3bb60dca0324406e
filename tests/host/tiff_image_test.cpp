#include "lightstage/host/io/tiff_image.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/testing/errors.hpp"
#include "lightstage/testing/paths.hpp"
#include "tiff_writer.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <tiffio.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <vector>

namespace lightstage {
namespace {

using testing::error_of;
using ::testing::HasSubstr;
using testing::write_tiff;
using testing::Written;

// A test image of `channels` channels in file order (R, G, B) with distinct values.
cv::Mat pattern(int rows, int cols, int channels, int depth) {
  cv::Mat image(rows, cols, CV_MAKETYPE(depth, channels));
  cv::randu(image, 0, depth == CV_8U ? 255 : depth == CV_16U ? 65535 : 4.0);
  return image;
}

cv::Mat bgr(const cv::Mat& rgb) {
  if (rgb.channels() == 1) return rgb;
  cv::Mat out;
  const int from_to[] = {0, 2, 1, 1, 2, 0};
  out.create(rgb.size(), rgb.type());
  cv::mixChannels(&rgb, 1, &out, 1, from_to, 3);
  return out;
}

struct Case {
  const char* name;
  int channels, depth;
  Written layout;
};

TEST(HostTiffImage, ReadsEveryLayoutItTakesAsStored) {
  const auto dir = testing::scratch_dir();
  const Case cases[] = {
      {"rgb16-strips", 3, CV_16U, {}},
      {"grey16", 1, CV_16U, {.photometric = PHOTOMETRIC_MINISBLACK}},
      {"rgb8-alpha", 3, CV_8U, {.bits = 8, .extra_samples = 1}},
      {"grey-float",
       1,
       CV_32F,
       {.bits = 32, .format = SAMPLEFORMAT_IEEEFP, .photometric = PHOTOMETRIC_MINISBLACK}},
      {"rgb16-planar", 3, CV_16U, {.planar = true}},
      {"rgb16-tiled", 3, CV_16U, {.tile = 16}},
      {"rgb16-planar-tiled-alpha", 3, CV_16U, {.extra_samples = 1, .planar = true, .tile = 16}},
      {"rgb16-deflate", 3, CV_16U, {.compression = COMPRESSION_ADOBE_DEFLATE}},
      {"rgb16-lzw", 3, CV_16U, {.compression = COMPRESSION_LZW}},
  };
  for (const Case& c : cases) {
    const cv::Mat rgb = pattern(37, 29, c.channels, c.depth);  // sides not a multiple of the tile
    const auto path = dir / (std::string(c.name) + ".tif");
    write_tiff(path, rgb, c.layout);
    const cv::Mat back = io::read_tiff(path);
    ASSERT_EQ(back.type(), rgb.type()) << c.name;
    EXPECT_EQ(cv::norm(back, bgr(rgb), cv::NORM_INF), 0) << c.name;
    EXPECT_EQ(io::read_tiff_size(path), rgb.size()) << c.name;
    // read_image dispatches on the name.
    EXPECT_EQ(cv::norm(io::read_image(path), bgr(rgb), cv::NORM_INF), 0) << c.name;
  }
}

TEST(HostTiffImage, RefusesWhatIsNotALinearCaptureNamingTheReason) {
  const auto dir = testing::scratch_dir();
  const struct {
    const char* name;
    int channels, depth;
    Written layout;
    const char* reason;
  } cases[] = {
      {"palette", 1, CV_8U, {.bits = 8, .photometric = PHOTOMETRIC_PALETTE}, "palette"},
      {"white", 1, CV_16U, {.photometric = PHOTOMETRIC_MINISWHITE}, "min-is-white"},
      {"signed", 1, CV_16U, {.format = SAMPLEFORMAT_INT, .photometric = PHOTOMETRIC_MINISBLACK}, "signed"},
      {"cfa", 1, CV_16U, {.photometric = PHOTOMETRIC_CFA}, "mosaic"},
  };
  for (const auto& c : cases) {
    const auto path = dir / (std::string(c.name) + ".tif");
    write_tiff(path, pattern(8, 8, c.channels, c.depth), c.layout);
    const std::string error = error_of([&] { io::read_tiff(path); });
    EXPECT_THAT(error, HasSubstr(path.string())) << c.name;
    EXPECT_THAT(error, HasSubstr(c.reason)) << c.name;
  }
}

TEST(HostTiffImage, RefusesBrokenFilesAndNonFiniteFloats) {
  const auto dir = testing::scratch_dir();
  EXPECT_THAT(error_of([&] { io::read_tiff(dir / "absent.tif"); }), HasSubstr("no such file"));

  const auto junk = dir / "junk.tif";
  std::ofstream(junk) << "this is not a TIFF file at all";
  EXPECT_THAT(error_of([&] { io::read_tiff(junk); }), HasSubstr("not a readable TIFF"));

  // The directory reads, the pixels do not: a deflate strip overwritten.
  const auto broken = dir / "broken.tif";
  write_tiff(broken, pattern(64, 64, 3, CV_16U), {.compression = COMPRESSION_ADOBE_DEFLATE});
  std::uint64_t offset = 0;
  {
    TIFF* tiff = TIFFOpen(broken.c_str(), "r");
    ASSERT_NE(tiff, nullptr);
    std::uint64_t* offsets = nullptr;
    ASSERT_EQ(TIFFGetField(tiff, TIFFTAG_STRIPOFFSETS, &offsets), 1);
    offset = offsets[0];
    TIFFClose(tiff);
  }
  {
    std::fstream file(broken, std::ios::in | std::ios::out | std::ios::binary);
    file.seekp(static_cast<std::streamoff>(offset));
    file << std::string(64, '\xff');
  }
  const std::string error = error_of([&] { io::read_tiff(broken); });
  EXPECT_THAT(error, HasSubstr(broken.string()));
  EXPECT_THAT(error, HasSubstr("cannot read rows 0 to 2"));

  // Tiles declared far larger than the image cost memory only: refused before allocating.
  const auto huge_tiles = dir / "huge-tiles.tif";
  {
    TIFF* tiff = TIFFOpen(huge_tiles.c_str(), "w");
    ASSERT_NE(tiff, nullptr);
    TIFFSetField(tiff, TIFFTAG_IMAGEWIDTH, 16u);
    TIFFSetField(tiff, TIFFTAG_IMAGELENGTH, 16u);
    TIFFSetField(tiff, TIFFTAG_BITSPERSAMPLE, static_cast<std::uint16_t>(16));
    TIFFSetField(tiff, TIFFTAG_SAMPLESPERPIXEL, static_cast<std::uint16_t>(1));
    TIFFSetField(tiff, TIFFTAG_PHOTOMETRIC, static_cast<std::uint16_t>(PHOTOMETRIC_MINISBLACK));
    TIFFSetField(tiff, TIFFTAG_COMPRESSION, static_cast<std::uint16_t>(COMPRESSION_ADOBE_DEFLATE));
    TIFFSetField(tiff, TIFFTAG_TILEWIDTH, 1024u);
    TIFFSetField(tiff, TIFFTAG_TILELENGTH, 1024u);
    std::vector<std::uint16_t> tile(1024u * 1024u, 1);
    ASSERT_GE(TIFFWriteTile(tiff, tile.data(), 0, 0, 0, 0), 0);
    TIFFClose(tiff);
  }
  EXPECT_THAT(error_of([&] { io::read_tiff(huge_tiles); }),
              HasSubstr("tiles of 1024x1024 do not fit a 16x16 image"));

  cv::Mat floats = pattern(8, 8, 1, CV_32F);
  floats.at<float>(3, 4) = std::numeric_limits<float>::quiet_NaN();
  const auto nan = dir / "nan.tif";
  write_tiff(nan, floats, {.bits = 32, .format = SAMPLEFORMAT_IEEEFP, .photometric = PHOTOMETRIC_MINISBLACK});
  EXPECT_THAT(error_of([&] { io::read_tiff(nan); }), HasSubstr("NaN"));
}

}  // namespace
}  // namespace lightstage
