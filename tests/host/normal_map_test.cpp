#include "lightstage/host/io/normal_map.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/geometry.hpp"
#include "lightstage/testing/paths.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <random>

namespace lightstage {
namespace {

cv::Mat random_normals(int rows, int cols, unsigned seed) {
  std::mt19937 rng(seed);
  cv::Mat normals(rows, cols, CV_32FC3);
  std::normal_distribution<double> gauss;
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < cols; ++x) {
      Vec3 n(gauss(rng), gauss(rng), gauss(rng));  // the whole sphere, back-facing too
      n.normalize();
      normals.at<cv::Vec3f>(y, x) =
          cv::Vec3f(static_cast<float>(n.x()), static_cast<float>(n.y()), static_cast<float>(n.z()));
    }
  }
  return normals;
}

TEST(HostNormalMap, RoundTripIsWithinQuantisation) {
  const auto dir = testing::scratch_dir();
  const cv::Mat normals = random_normals(64, 48, 1);
  cv::Mat mask(normals.size(), CV_8UC1, cv::Scalar::all(255));
  mask(cv::Rect(0, 0, 10, 10)).setTo(0);
  io::write_normal_map(dir / "n.png", normals, mask);
  const auto decoded = io::read_normal_map(dir / "n.png");
  ASSERT_EQ(decoded.normals.type(), CV_32FC3);
  double worst = 0;
  for (int y = 0; y < normals.rows; ++y) {
    for (int x = 0; x < normals.cols; ++x) {
      const bool inside = mask.at<std::uint8_t>(y, x) != 0;
      ASSERT_EQ(decoded.valid.at<std::uint8_t>(y, x) != 0, inside) << x << "," << y;
      if (!inside) {
        ASSERT_EQ(decoded.normals.at<cv::Vec3f>(y, x), cv::Vec3f(0, 0, 0));
        continue;
      }
      const auto a = normals.at<cv::Vec3f>(y, x), b = decoded.normals.at<cv::Vec3f>(y, x);
      worst = std::max(worst, angle_between_deg(Vec3(a[0], a[1], a[2]), Vec3(b[0], b[1], b[2])));
    }
  }
  EXPECT_LT(worst, 0.003);
  EXPECT_GT(worst, 0.0);  // it is quantised, really
}

TEST(HostNormalMap, RedHoldsXAndValuesFollowTheFormula) {
  const auto dir = testing::scratch_dir();
  cv::Mat normals(2, 2, CV_32FC3, cv::Scalar::all(0));
  normals.at<cv::Vec3f>(0, 0) = cv::Vec3f(1, 0, 0);  // +x
  normals.at<cv::Vec3f>(0, 1) = cv::Vec3f(0, 1, 0);  // +y (up)
  normals.at<cv::Vec3f>(1, 0) = cv::Vec3f(0, 0, 1);  // toward the camera
  // (1, 1) stays zero: no normal.
  io::write_normal_map(dir / "axes.png", normals);
  const cv::Mat raw = cv::imread((dir / "axes.png").string(), cv::IMREAD_UNCHANGED);  // BGR
  ASSERT_EQ(raw.type(), CV_16UC3);
  EXPECT_EQ(raw.at<cv::Vec3w>(0, 0), cv::Vec3w(32768, 32768, 65535));  // B, G, R: R = x = 1
  EXPECT_EQ(raw.at<cv::Vec3w>(0, 1), cv::Vec3w(32768, 65535, 32768));
  EXPECT_EQ(raw.at<cv::Vec3w>(1, 0), cv::Vec3w(65535, 32768, 32768));
  EXPECT_EQ(raw.at<cv::Vec3w>(1, 1), cv::Vec3w(0, 0, 0));

  const auto decoded = io::read_normal_map(dir / "axes.png");
  EXPECT_NEAR(decoded.normals.at<cv::Vec3f>(0, 0)[0], 1.0f, 1e-4f);
  EXPECT_EQ(decoded.valid.at<std::uint8_t>(1, 1), 0);
  EXPECT_EQ(cv::countNonZero(decoded.valid), 3);
}

TEST(HostNormalMap, VisualisationIs8BitWithRedForX) {
  cv::Mat normals(1, 2, CV_32FC3, cv::Scalar::all(0));
  normals.at<cv::Vec3f>(0, 0) = cv::Vec3f(1, 0, 0);
  const cv::Mat picture = io::normal_visualisation(normals);
  ASSERT_EQ(picture.type(), CV_8UC3);
  EXPECT_EQ(picture.at<cv::Vec3b>(0, 0), cv::Vec3b(128, 128, 255));
  EXPECT_EQ(picture.at<cv::Vec3b>(0, 1), cv::Vec3b(0, 0, 0));
}

TEST(HostNormalMap, RejectsNonNormalImages) {
  const auto dir = testing::scratch_dir();
  ASSERT_TRUE(cv::imwrite((dir / "grey.png").string(), cv::Mat(3, 3, CV_16UC1, cv::Scalar::all(7))));
  try {
    io::read_normal_map(dir / "grey.png");
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("grey.png"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace lightstage
