#include "lightstage/host/eval/angular_error.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/geometry.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/normal_map.hpp"
#include "lightstage/testing/paths.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace lightstage {
namespace {

cv::Vec3f tilted(double degrees) {
  const Vec3 n = direction_from_elevation_azimuth(rad_from_deg(90 - degrees), 0.3);
  return {static_cast<float>(n.x()), static_cast<float>(n.y()), static_cast<float>(n.z())};
}

TEST(HostAngularError, StatsOverPixelsWhereBothHaveNormals) {
  // 11 pixels in a row: predictions tilted 0..10 degrees from (0,0,1).
  cv::Mat truth(1, 13, CV_32FC3, cv::Scalar(0, 0, 1));
  cv::Mat predicted(1, 13, CV_32FC3, cv::Scalar::all(0));
  for (int i = 0; i <= 10; ++i) predicted.at<cv::Vec3f>(0, i) = tilted(i);
  // Pixel 11 has truth but no prediction (missing); pixel 12 is outside the mask.
  cv::Mat mask(1, 13, CV_8UC1, cv::Scalar::all(255));
  mask.at<std::uint8_t>(0, 12) = 0;
  predicted.at<cv::Vec3f>(0, 12) = tilted(80);
  const auto map = angular_error(predicted, truth, mask);
  EXPECT_EQ(map.stats.count, 11u);
  EXPECT_EQ(map.stats.missing, 1u);
  EXPECT_NEAR(map.stats.mean, 5.0, 1e-4);
  EXPECT_NEAR(map.stats.median, 5.0, 1e-4);
  EXPECT_NEAR(map.stats.p90, 9.0, 1e-4);
  EXPECT_NEAR(map.stats.max, 10.0, 1e-4);
  EXPECT_NEAR(map.degrees.at<float>(0, 3), 3.0, 1e-4);
  EXPECT_EQ(map.valid.at<std::uint8_t>(0, 11), 0);
  EXPECT_EQ(map.valid.at<std::uint8_t>(0, 12), 0);
  const auto json = map.stats.to_json();
  EXPECT_EQ(json["count"], 11);
  EXPECT_TRUE(json.contains("mean_deg") && json.contains("median_deg") && json.contains("p90_deg"));
}

// The quantiles interpolate between order statistics as over the sorted errors,
// whatever order the pixels come in, with ties and for odd and even counts.
TEST(HostAngularError, QuantilesMatchTheSortedErrorsInAnyOrder) {
  std::mt19937 random(7);
  for (const int count : {1, 2, 3, 10, 11, 100, 257}) {
    cv::Mat truth(1, count, CV_32FC3, cv::Scalar(0, 0, 1));
    cv::Mat predicted(1, count, CV_32FC3);
    std::uniform_int_distribution<int> tilt(0, count < 10 ? 40 : 4 * count);
    for (int i = 0; i < count; ++i) predicted.at<cv::Vec3f>(0, i) = tilted(0.25 * tilt(random));
    const AngularErrorMap map =
        angular_error(predicted, truth, cv::Mat(1, count, CV_8UC1, cv::Scalar::all(255)));
    std::vector<double> sorted(map.degrees.begin<float>(), map.degrees.end<float>());
    std::sort(sorted.begin(), sorted.end());
    const auto quantile = [&](double q) {
      const double position = q * (count - 1);
      const auto below = static_cast<std::size_t>(position);
      const double upper = sorted[std::min<std::size_t>(below + 1, sorted.size() - 1)];
      return sorted[below] + (upper - sorted[below]) * (position - static_cast<double>(below));
    };
    SCOPED_TRACE(count);
    // The map holds floats, the statistics doubles: the same angles up to float rounding.
    EXPECT_NEAR(map.stats.median, quantile(0.5), 1e-4);
    EXPECT_NEAR(map.stats.p90, quantile(0.9), 1e-4);
    EXPECT_NEAR(map.stats.max, sorted.back(), 1e-4);
  }
}

TEST(HostAngularError, EvaluatesFilesAgainstAGroundTruthFolder) {
  const auto dir = testing::scratch_dir();
  cv::Mat truth(4, 4, CV_32FC3, cv::Scalar(0, 0, 1));
  cv::Mat predicted(4, 4, CV_32FC3);
  predicted.setTo(cv::Scalar(tilted(2)[0], tilted(2)[1], tilted(2)[2]));
  cv::Mat mask(4, 4, CV_8UC1, cv::Scalar::all(0));
  mask(cv::Rect(0, 0, 2, 4)).setTo(255);
  std::filesystem::create_directory(dir / "gt");
  io::write_normal_map(dir / "gt" / "Normal_gt.png", truth);
  io::write_png(dir / "gt" / "mask.png", mask);
  io::write_normal_map(dir / "pred.png", predicted);
  const auto stats = evaluate_normal_map(dir / "pred.png", dir / "gt");
  EXPECT_EQ(stats.count, 8u);
  EXPECT_NEAR(stats.mean, 2.0, 0.003);

  try {
    evaluate_normal_map(dir / "missing.png", dir / "gt");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("missing.png"), std::string::npos);
  }
  io::write_normal_map(dir / "small.png", cv::Mat(2, 2, CV_32FC3, cv::Scalar(0, 0, 1)));
  try {
    evaluate_normal_map(dir / "small.png", dir / "gt");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("small.png"), std::string::npos);
  }
}

TEST(HostAngularError, SizeMismatchIsAnInputError) {
  EXPECT_THROW(angular_error(cv::Mat(2, 2, CV_32FC3), cv::Mat(3, 3, CV_32FC3)), InputError);
}

}  // namespace
}  // namespace lightstage
