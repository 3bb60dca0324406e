#include "lightstage/host/io/stack_bands.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/radiometry.hpp"
#include "lightstage/testing/errors.hpp"
#include "lightstage/testing/paths.hpp"
#include "stack_fixture.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>

namespace lightstage {
namespace {

using testing::error_of;
using ::testing::HasSubstr;

void expect_same_pixels(const cv::Mat& band, const cv::Mat& whole, int y0, const std::string& what) {
  ASSERT_EQ(band.type(), whole.type()) << what;
  ASSERT_EQ(band.cols, whole.cols) << what;
  EXPECT_EQ(cv::norm(band, whole.rowRange(y0, y0 + band.rows), cv::NORM_INF), 0) << what << " at row " << y0;
}

// Every band of `dir`, read top to bottom `rows` at a time, equals the same rows of load_stack.
void expect_bands_equal_whole(const std::filesystem::path& dir, int rows) {
  const ImageStack whole = io::load_stack(dir);
  io::StackBands bands(dir);
  ASSERT_EQ(bands.size(), cv::Size(whole.width(), whole.height()));
  ASSERT_EQ(bands.type(), whole.frames.front().image.type());
  for (int y0 = 0; y0 < whole.height(); y0 += rows) {
    const int n = std::min(rows, whole.height() - y0);
    const ImageStack band = bands.read_band(y0, n);
    ASSERT_EQ(band.frames.size(), whole.frames.size());
    for (std::size_t i = 0; i < band.frames.size(); ++i) {
      const Frame& a = band.frames[i];
      const Frame& b = whole.frames[i];
      EXPECT_EQ(a.filename, b.filename);
      EXPECT_EQ(a.light_direction, b.light_direction);
      EXPECT_EQ(a.light_intensity, b.light_intensity);
      EXPECT_EQ(a.led_id, b.led_id);
      EXPECT_EQ(a.led_position_mm, b.led_position_mm);
      EXPECT_EQ(a.black_level, b.black_level);
      EXPECT_EQ(a.saturation_level, b.saturation_level);
      EXPECT_EQ(a.exposure_us, b.exposure_us);
      EXPECT_EQ(a.dark_file, b.dark_file);
      ASSERT_EQ(a.image.rows, n);
      expect_same_pixels(a.image, b.image, y0, a.filename);
      ASSERT_EQ(a.dark.empty(), b.dark.empty());
      if (!a.dark.empty()) expect_same_pixels(a.dark, b.dark, y0, a.dark_file);
    }
    ASSERT_EQ(band.mask.empty(), whole.mask.empty());
    if (!band.mask.empty()) expect_same_pixels(band.mask, whole.mask, y0, "mask");
    ASSERT_EQ(band.ground_truth.has_value(), whole.ground_truth.has_value());
    if (band.ground_truth) {
      expect_same_pixels(band.ground_truth->normals, whole.ground_truth->normals, y0, "normals");
      expect_same_pixels(band.ground_truth->depth, whole.ground_truth->depth, y0, "depth");
    }
  }
}

ImageStack stack_with_darks(int type) {
  ImageStack stack = testing::small_stack(5, type, 23, 17);
  cv::Mat dark_a(stack.frames[0].image.size(), type), dark_b(stack.frames[0].image.size(), type);
  cv::RNG rng(3);
  rng.fill(dark_a, cv::RNG::UNIFORM, 0, CV_MAT_DEPTH(type) == CV_32F ? 0.01 : 60);
  rng.fill(dark_b, cv::RNG::UNIFORM, 0, CV_MAT_DEPTH(type) == CV_32F ? 0.01 : 60);
  const char* extension = CV_MAT_DEPTH(type) == CV_32F ? "pfm" : "png";
  for (std::size_t i = 0; i < stack.frames.size(); ++i) {
    stack.frames[i].dark = i < 2 ? dark_a : dark_b;
    stack.frames[i].dark_file = fmt::format("dark_{}us.{}", i < 2 ? 1000 : 2000, extension);
  }
  return stack;
}

TEST(HostStackBands, SixteenBitColourBandsEqualTheWholeStack) {
  const auto dir = testing::scratch_dir() / "stack";
  io::write_stack(dir, stack_with_darks(CV_16UC3));
  for (int rows : {1, 4, 7, 17}) expect_bands_equal_whole(dir, rows);
}

TEST(HostStackBands, EightBitGreyAndFloatBandsEqualTheWholeStack) {
  for (int type : {CV_8UC1, CV_32FC1, CV_32FC3}) {
    const auto dir = testing::scratch_dir() / fmt::format("stack_{}", type);
    ImageStack stack = stack_with_darks(type);
    if (CV_MAT_DEPTH(type) == CV_32F) {
      for (auto& frame : stack.frames) {
        frame.image.convertTo(frame.image, type, 1.0 / 65536);
        frame.filename = frame.filename.substr(0, frame.filename.size() - 4) + ".pfm";
      }
    }
    io::write_stack(dir, stack);
    expect_bands_equal_whole(dir, 5);
  }
}

TEST(HostStackBands, BandObservationsAreTheRowsOfTheWholeObservations) {
  const auto dir = testing::scratch_dir() / "stack";
  io::write_stack(dir, stack_with_darks(CV_16UC3));
  const Observations whole = make_observations(io::load_stack(dir));
  io::StackBands bands(dir);
  std::size_t next = 0;
  for (int y0 = 0; y0 < bands.size().height; y0 += 6) {
    const int rows = std::min(6, bands.size().height - y0);
    const Observations band = make_observations(bands.read_band(y0, rows));
    for (std::size_t p = 0; p < band.pixel_count(); ++p, ++next) {
      ASSERT_LT(next, whole.pixel_count());
      const auto q = static_cast<Eigen::Index>(next);
      const auto r = static_cast<Eigen::Index>(p);
      EXPECT_EQ(band.pixels[p] + cv::Point(0, y0), whole.pixels[next]);
      EXPECT_EQ(band.intensities.row(r), whole.intensities.row(q));
      EXPECT_EQ(band.saturated.row(r), whole.saturated.row(q));
      EXPECT_EQ(band.chroma.row(r), whole.chroma.row(q));
    }
    EXPECT_EQ(band.lights, whole.lights);
  }
  EXPECT_EQ(next, whole.pixel_count());
}

TEST(HostStackBands, ANonFinitePixelIsNamedAtItsRowInTheWholeImage) {
  const auto dir = testing::scratch_dir() / "stack";
  ImageStack stack = testing::small_stack(3, CV_32FC1, 8, 12);
  for (auto& frame : stack.frames) frame.filename = frame.filename.substr(0, 6) + ".pfm";
  io::write_stack(dir, stack);
  cv::Mat broken = stack.frames[1].image.clone();
  broken.at<float>(9, 2) = std::numeric_limits<float>::quiet_NaN();
  io::write_pfm(dir / stack.frames[1].filename, broken);
  io::StackBands bands(dir);
  EXPECT_NO_THROW(bands.read_band(0, 8));
  const std::string error = error_of([&] { bands.read_band(8, 4); });
  EXPECT_THAT(error, HasSubstr(stack.frames[1].filename));
  EXPECT_THAT(error, HasSubstr("pixel (2, 9) is NaN"));
}

TEST(HostStackBands, FramesOfAnotherTypeAreRefusedAtTheFirstBandAMissingDarkWhenOpened) {
  const auto dir = testing::scratch_dir() / "stack";
  ImageStack stack = stack_with_darks(CV_16UC3);
  io::write_stack(dir, stack);
  cv::Mat grey;
  cv::extractChannel(stack.frames[2].image, grey, 0);
  io::write_png(dir / stack.frames[2].filename, grey);
  std::string error = error_of([&] { io::StackBands(dir).read_band(0, 1); });
  EXPECT_THAT(error, HasSubstr(stack.frames[2].filename));
  EXPECT_THAT(error, HasSubstr("16-bit grey"));

  io::write_png(dir / stack.frames[2].filename, stack.frames[2].image);
  std::filesystem::remove(dir / "dark_2000us.png");
  error = error_of([&] { io::StackBands bands(dir); });
  EXPECT_THAT(error, HasSubstr("dark_2000us.png"));
  EXPECT_THAT(error, HasSubstr("not in the stack folder"));
}

TEST(HostStackBands, RowsOutsideTheImagesAreRefused) {
  const auto dir = testing::scratch_dir() / "stack";
  io::write_stack(dir, testing::small_stack());
  io::StackBands bands(dir);
  EXPECT_THAT(error_of([&] { bands.read_band(4, 3); }), HasSubstr("outside"));
  EXPECT_THAT(error_of([&] { bands.read_band(-1, 2); }), HasSubstr("outside"));
}

}  // namespace
}  // namespace lightstage
