// Calibration stacks read in parts (calibration_images.hpp): the median and
// brightest images made a band of rows at a time are the whole stack's, a
// region is the whole images cut to it, and what does not fit is named.
#include "lightstage/host/calibration/calibration_images.hpp"

#include "lightstage/host/io/image_io.hpp"
#include "lightstage/testing/errors.hpp"
#include "lightstage/testing/paths.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <fstream>
#include <random>

namespace lightstage::calibration {
namespace {

namespace fs = std::filesystem;
using testing::error_of;

// `count` 16-bit colour frames of noise with one bright, clipped spot each, as a calibration stack.
fs::path write_noise_stack(const fs::path& dir, int count, cv::Size size) {
  fs::create_directories(dir);
  std::mt19937 random(7);
  std::uniform_int_distribution<int> value(0, 40000);
  std::ofstream names(dir / "filenames.txt");
  for (int i = 0; i < count; ++i) {
    cv::Mat image(size, CV_16UC3);
    for (int y = 0; y < size.height; ++y)
      for (int x = 0; x < size.width; ++x)
        image.at<cv::Vec3w>(y, x) =
            cv::Vec3w(static_cast<std::uint16_t>(value(random)), static_cast<std::uint16_t>(value(random)),
                      static_cast<std::uint16_t>(value(random)));
    cv::circle(image, {(i * 7) % size.width, (i * 5) % size.height}, 3, cv::Scalar::all(65535), -1);
    const std::string name = "frame" + std::to_string(i) + ".png";
    io::write_png16(dir / name, image);
    names << name << "\n";
  }
  return dir;
}

void expect_same(const cv::Mat& a, const cv::Mat& b, const char* what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  ASSERT_EQ(a.type(), b.type()) << what;
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0) << what;
}

TEST(CalibrationImages, ViewsMadeInBandsAreTheWholeStacksMedianAndMaximum) {
  const fs::path stack = write_noise_stack(testing::scratch_dir() / "stack", 9, {37, 29});
  const CalibrationImages whole = load_calibration_images(stack);
  const CalibrationImages index = load_calibration_index(stack);
  EXPECT_TRUE(index.grey.empty());
  EXPECT_EQ(index.image_size, cv::Size(37, 29));
  EXPECT_EQ(index.size(), 9u);
  // 1 kB of decoded images at a time: bands of one row.
  const CalibrationViews views = calibration_views(index, 2, 1024);
  expect_same(views.median, median_image(whole.grey), "median");
  expect_same(views.maximum, max_image(whole.grey), "maximum");
  const CalibrationViews one_band = calibration_views(index, 1);
  expect_same(one_band.median, views.median, "median in one band");
}

TEST(CalibrationImages, ARegionIsTheWholeImagesCutToIt) {
  const fs::path stack = write_noise_stack(testing::scratch_dir() / "stack", 4, {40, 30});
  const CalibrationImages whole = load_calibration_images(stack);
  CalibrationImages part = load_calibration_index(stack);
  const cv::Rect region(5, 11, 17, 9);
  load_calibration_pixels(part, region, 2);
  EXPECT_EQ(part.region, region);
  ASSERT_EQ(part.grey.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    expect_same(part.grey[i], whole.grey[i](region), "grey");
    expect_same(part.saturated[i], whole.saturated[i](region), "saturated");
  }
  EXPECT_GT(cv::countNonZero(whole.saturated[0]), 0) << "the test's spots must clip";
  const std::string error = error_of([&] { load_calibration_pixels(part, cv::Rect(30, 20, 11, 5)); });
  EXPECT_NE(error.find("region 11x5 at (30, 20) is not inside the 40x30 images"), std::string::npos) << error;
}

TEST(CalibrationImages, AnImageOfAnotherSizeIsNamedWhereverItIsRead) {
  const fs::path stack = write_noise_stack(testing::scratch_dir() / "stack", 3, {20, 16});
  io::write_png16(stack / "frame2.png", cv::Mat(15, 20, CV_16UC3, cv::Scalar::all(100)));
  const CalibrationImages index = load_calibration_index(stack);  // the first image's header only
  for (const std::string& error :
       {error_of([&] { calibration_views(index); }), error_of([&] { load_calibration_images(stack); })}) {
    EXPECT_NE(error.find("frame2.png: image is 20x15"), std::string::npos) << error;
    EXPECT_NE(error.find("but frame0.png is 20x16"), std::string::npos) << error;
  }
}

}  // namespace
}  // namespace lightstage::calibration
