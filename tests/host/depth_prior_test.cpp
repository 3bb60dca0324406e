// Depth priors from EXR files (issue 7): written here with OpenCV, the library
// the loader reads them with, and read back through load_depth_prior — FLOAT
// and HALF, the channel names the loader accepts (Y, Z, R) and the ones it
// refuses, holes, perspective depth, and errors that name the file and channel.
#include "lightstage/host/surface/depth_prior.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/surface/camera.hpp"
#include "lightstage/testing/errors.hpp"
#include "lightstage/testing/paths.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace lightstage::surface {
namespace {

using testing::error_of;

// OpenCV's EXR codec may be off by default (OPENCV_IO_ENABLE_OPENEXR, read on
// the first EXR use): this test writes before the loader's first read, so it
// enables the codec itself, the same way.
void write_exr(const std::filesystem::path& path, const cv::Mat& image, bool half = false) {
  ::setenv("OPENCV_IO_ENABLE_OPENEXR", "1", 0);
  std::vector<int> params{cv::IMWRITE_EXR_TYPE,
                          half ? cv::IMWRITE_EXR_TYPE_HALF : cv::IMWRITE_EXR_TYPE_FLOAT};
  ASSERT_TRUE(cv::imwrite(path.string(), image, params)) << path;
}

std::vector<char> read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const std::filesystem::path& path, const std::vector<char>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// Renames the one channel of a single-channel EXR that OpenCV wrote (as "Y")
// to another one-letter name: the channel list is "channels\0chlist\0" + size,
// then the first channel's name.
void rename_channel(const std::filesystem::path& path, char name) {
  std::vector<char> bytes = read_bytes(path);
  const std::string key("channels\0chlist\0", 16);
  const auto at = std::search(bytes.begin(), bytes.end(), key.begin(), key.end());
  ASSERT_NE(at, bytes.end()) << path;
  char& first = *(at + static_cast<std::ptrdiff_t>(key.size()) + 4);
  ASSERT_EQ(first, 'Y');
  first = name;
  write_bytes(path, bytes);
}

// A 12x10 depth ramp with a zero and a NaN hole.
cv::Mat ramp() {
  cv::Mat depth(10, 12, CV_32FC1);
  for (int r = 0; r < depth.rows; ++r)
    for (int c = 0; c < depth.cols; ++c)
      depth.at<float>(r, c) = 40.0f + 0.25f * static_cast<float>(c + 3 * r);
  depth.at<float>(2, 3) = 0;
  depth.at<float>(7, 9) = std::nanf("");
  return depth;
}

const CameraModel kCamera = CameraModel::orthographic(cv::Size(12, 10), 0.5);

TEST(DepthPriorExr, FloatDepthReadsBackExactlyWithItsHoles) {
  const auto dir = testing::scratch_dir();
  const cv::Mat depth = ramp();
  write_exr(dir / "d.exr", depth);
  const DepthMap prior = load_depth_prior(dir / "d.exr", kCamera);
  ASSERT_EQ(prior.depth.size(), kCamera.size);
  EXPECT_EQ(cv::countNonZero(prior.valid), 12 * 10 - 2);
  EXPECT_EQ(prior.valid.at<std::uint8_t>(2, 3), 0);
  EXPECT_EQ(prior.valid.at<std::uint8_t>(7, 9), 0);
  for (int r = 0; r < depth.rows; ++r)
    for (int c = 0; c < depth.cols; ++c)
      if (prior.valid.at<std::uint8_t>(r, c)) {
        EXPECT_EQ(prior.depth.at<float>(r, c), depth.at<float>(r, c));
      }
  // The same depth as a PFM gives the same prior (so `solve --prior` and
  // `integrate --prior` see no difference between the formats).
  io::write_pfm(dir / "d.pfm", depth);
  const DepthMap pfm = load_depth_prior(dir / "d.pfm", kCamera);
  EXPECT_EQ(cv::norm(pfm.depth, prior.depth, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(pfm.valid, prior.valid, cv::NORM_INF), 0.0);
}

TEST(DepthPriorExr, HalfDepthReadsToHalfPrecision) {
  const auto dir = testing::scratch_dir();
  const cv::Mat depth = ramp();
  write_exr(dir / "h.exr", depth, true);
  const DepthMap prior = load_depth_prior(dir / "h.exr", kCamera);
  EXPECT_EQ(cv::countNonZero(prior.valid), 12 * 10 - 2);
  for (int r = 0; r < depth.rows; ++r)
    for (int c = 0; c < depth.cols; ++c)
      if (prior.valid.at<std::uint8_t>(r, c)) {  // half: 11 significant bits
        EXPECT_NEAR(prior.depth.at<float>(r, c), depth.at<float>(r, c), depth.at<float>(r, c) / 1024);
      }
}

TEST(DepthPriorExr, ZAndRChannelsAreDepthToo) {
  const auto dir = testing::scratch_dir();
  const cv::Mat depth = ramp();
  for (const char name : {'Z', 'R'}) {
    const auto path = dir / fmt::format("{}.exr", name);
    write_exr(path, depth);
    rename_channel(path, name);
    const DepthMap prior = load_depth_prior(path, kCamera);
    EXPECT_EQ(cv::countNonZero(prior.valid), 12 * 10 - 2) << name;
    EXPECT_EQ(prior.depth.at<float>(9, 11), depth.at<float>(9, 11)) << name;
  }
}

TEST(DepthPriorExr, PerspectiveDepthMustBePositive) {
  const auto dir = testing::scratch_dir();
  cv::Mat depth = ramp();
  depth.at<float>(0, 0) = -5;
  write_exr(dir / "p.exr", depth);
  Mat3 K;
  K << 20, 0, 5.5, 0, 20, 4.5, 0, 0, 1;
  const DepthMap prior = load_depth_prior(dir / "p.exr", CameraModel::perspective(cv::Size(12, 10), K));
  EXPECT_EQ(prior.valid.at<std::uint8_t>(0, 0), 0);
  EXPECT_EQ(cv::countNonZero(prior.valid), 12 * 10 - 3);
}

TEST(DepthPriorExr, ErrorsNameTheFileAndTheChannel) {
  const auto dir = testing::scratch_dir();
  const cv::Mat depth = ramp();
  // Colour: OpenCV writes B, G, R.
  cv::Mat colour;
  cv::merge(std::vector<cv::Mat>{depth, depth, depth}, colour);
  write_exr(dir / "rgb.exr", colour);
  EXPECT_NE(error_of([&] {
              load_depth_prior(dir / "rgb.exr", kCamera);
            }).find("rgb.exr: a depth EXR must have one channel (named Y, Z or R), this has 3 (B, G, R)"),
            std::string::npos);
  write_exr(dir / "v.exr", depth);
  rename_channel(dir / "v.exr", 'V');
  EXPECT_NE(error_of([&] {
              load_depth_prior(dir / "v.exr", kCamera);
            }).find("v.exr: EXR channel 'V': a depth channel must be named Y, Z or R"),
            std::string::npos);
  write_exr(dir / "small.exr", depth(cv::Rect(0, 0, 8, 10)));
  EXPECT_NE(error_of([&] {
              load_depth_prior(dir / "small.exr", kCamera);
            }).find("small.exr: depth prior is 8x10 but the images are 12x10"),
            std::string::npos);
  write_exr(dir / "empty.exr", cv::Mat::zeros(10, 12, CV_32FC1));
  EXPECT_NE(error_of([&] { load_depth_prior(dir / "empty.exr", kCamera); }).find("holds no valid depth"),
            std::string::npos);
  write_bytes(dir / "text.exr", {'n', 'o', 't', ' ', 'e', 'x', 'r', '\n'});
  EXPECT_NE(
      error_of([&] { load_depth_prior(dir / "text.exr", kCamera); }).find("text.exr: not an OpenEXR file"),
      std::string::npos);
  // Cut inside the header, then inside the pixels.
  std::vector<char> bytes = read_bytes(dir / "small.exr");
  write_bytes(dir / "cut-header.exr", std::vector<char>(bytes.begin(), bytes.begin() + 40));
  EXPECT_NE(error_of([&] {
              load_depth_prior(dir / "cut-header.exr", kCamera);
            }).find("cut-header.exr: EXR header ends inside"),
            std::string::npos);
  write_exr(dir / "d.exr", depth);
  bytes = read_bytes(dir / "d.exr");
  write_bytes(dir / "cut-pixels.exr", std::vector<char>(bytes.begin(), bytes.end() - 64));
  EXPECT_NE(error_of([&] {
              load_depth_prior(dir / "cut-pixels.exr", kCamera);
            }).find("cut-pixels.exr: cannot decode EXR channel 'Y'"),
            std::string::npos);
  EXPECT_NE(error_of([&] { load_depth_prior(dir / "missing.exr", kCamera); }).find("missing.exr"),
            std::string::npos);
}

}  // namespace
}  // namespace lightstage::surface
