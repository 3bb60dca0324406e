#include "lightstage/host/capture/hdr_merge.hpp"

#include "lightstage/common/error.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace lightstage {
namespace {

constexpr int kWidth = 64, kHeight = 8;

// Radiance in DN per second: a ramp over 4.6 decades along x.
double radiance(int x, int y) { return 2e4 * std::pow(10.0, 4.6 * x / (kWidth - 1)) * (1 + 0.01 * y); }

// Non-uniform dark: a gradient plus column offsets.
cv::Mat make_dark() {
  cv::Mat dark(kHeight, kWidth, CV_16UC1);
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x)
      dark.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>(300 + 5 * x + 20 * y + (x % 3 == 0 ? 80 : 0));
  }
  return dark;
}

// A linear 16-bit sensor: dark + radiance · t, rounded and clipped at 65535.
cv::Mat expose(const cv::Mat& dark, double exposure_us) {
  cv::Mat raw(kHeight, kWidth, CV_16UC1);
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      const double v = dark.at<std::uint16_t>(y, x) + radiance(x, y) * exposure_us * 1e-6;
      raw.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>(std::min(65535.0, std::round(v)));
    }
  }
  return raw;
}

TEST(CaptureHdrMerge, MergedValuesAreRadiancePerSecondAndClippedEverywhereIsFlagged) {
  const cv::Mat dark = make_dark();
  const std::vector<double> exposures = {250, 2000, 16000};
  std::vector<HdrSample> samples;
  for (const double e : exposures) samples.push_back({expose(dark, e), dark, e});
  const HdrMerge merged = merge_hdr(samples);
  ASSERT_EQ(merged.image.type(), CV_32FC1);
  EXPECT_FLOAT_EQ(static_cast<float>(merged.saturation_level), static_cast<float>(1.0 / 250e-6));
  const double clip = 0.98 * 65535;
  std::size_t expected_saturated = 0;
  double worst = 0;
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      const double value = merged.image.at<float>(y, x);
      const double truth = radiance(x, y) / 65535.0;
      if (dark.at<std::uint16_t>(y, x) + radiance(x, y) * 250e-6 >= clip) {
        ++expected_saturated;
        EXPECT_EQ(value, merged.saturation_level) << x << "," << y;
        continue;
      }
      EXPECT_LT(value, merged.saturation_level);
      worst = std::max(worst, std::abs(value / truth - 1));
    }
  }
  EXPECT_GT(expected_saturated, 0u) << "the ramp must clip at the shortest exposure too";
  EXPECT_EQ(merged.saturated_values, expected_saturated);
  // Rounding to whole DN: the darkest pixels record 320 DN at 16 ms, 0.5 DN
  // of which is 0.16%; everywhere else the error is smaller.
  EXPECT_LT(worst, 2.5e-3);
  RecordProperty("worst_relative_error", std::to_string(worst));
  ASSERT_EQ(merged.clipped.size(), 3u);
  EXPECT_GT(merged.clipped[2], merged.clipped[1]);
  EXPECT_GT(merged.clipped[1], merged.clipped[0]);
}

TEST(CaptureHdrMerge, ClippedSamplesAreIgnoredAndTheDarkOfEachExposureSubtracted) {
  // Two exposures with darks of their own (dark current grows with exposure).
  cv::Mat dark_short(1, 2, CV_16UC1, cv::Scalar::all(100)), dark_long(1, 2, CV_16UC1, cv::Scalar::all(900));
  cv::Mat short_frame(1, 2, CV_16UC1), long_frame(1, 2, CV_16UC1);
  short_frame.at<std::uint16_t>(0, 0) = 100 + 1000;  // 1000 DN in 1 ms
  long_frame.at<std::uint16_t>(0, 0) = 900 + 8000;   // 8000 DN in 8 ms: the same radiance
  short_frame.at<std::uint16_t>(0, 1) = 100 + 30000;
  long_frame.at<std::uint16_t>(0, 1) = 65535;  // clipped: only the short sample counts
  const HdrMerge merged = merge_hdr({{short_frame, dark_short, 1000}, {long_frame, dark_long, 8000}});
  EXPECT_NEAR(merged.image.at<float>(0, 0), 1000 / 65535.0 / 1e-3, 1e-3);
  EXPECT_NEAR(merged.image.at<float>(0, 1), 30000 / 65535.0 / 1e-3, 1e-3);
  EXPECT_EQ(merged.saturated_values, 0u);
  EXPECT_EQ(merged.clipped[1], 1u);
}

TEST(CaptureHdrMerge, AllDarkPixelsTakeTheLongestExposure) {
  cv::Mat zero(1, 1, CV_16UC1, cv::Scalar::all(0)), one(1, 1, CV_16UC1, cv::Scalar::all(0));
  const HdrMerge merged = merge_hdr({{zero, {}, 100}, {one, {}, 1000}});
  EXPECT_EQ(merged.image.at<float>(0, 0), 0.0f);
  EXPECT_EQ(merged.saturated_values, 0u);
}

// A camera with a gamma of 2.2 and 8-bit codes: linearised through its
// inverse response first, then merged; the dark is in the linear domain.
TEST(CaptureHdrMerge, NonLinearCamerasAreLinearisedBeforeMerging) {
  std::vector<double> knots(256);
  for (std::size_t k = 0; k < knots.size(); ++k) knots[k] = std::pow(static_cast<double>(k) / 255.0, 2.2);
  const InverseResponse response(8, knots);
  const std::vector<double> exposures = {1000, 4000, 16000};
  std::vector<HdrSample> samples;
  for (const double e : exposures) {
    cv::Mat raw(1, kWidth, CV_8UC1);
    for (int x = 0; x < kWidth; ++x) {
      const double linear = std::min(1.0, 0.02 + radiance(x, 0) / 65535.0 * e * 1e-6);
      raw.at<std::uint8_t>(0, x) = static_cast<std::uint8_t>(std::round(255 * std::pow(linear, 1 / 2.2)));
    }
    samples.push_back({raw, cv::Mat(1, kWidth, CV_32FC1, cv::Scalar::all(0.02)), e});
  }
  HdrMergeOptions options;
  options.response = &response;
  const HdrMerge merged = merge_hdr(samples, options);
  double worst = 0;
  int compared = 0;
  for (int x = 0; x < kWidth; ++x) {
    const double truth = radiance(x, 0) / 65535.0;
    if (0.02 + truth * 1000e-6 >= 0.9) continue;  // near or past clipping at every exposure
    if (truth * 16000e-6 < 0.1) continue;         // 8-bit codes cannot resolve the darkest
    worst = std::max(worst, std::abs(merged.image.at<float>(0, x) / truth - 1));
    ++compared;
  }
  EXPECT_GT(compared, 20);
  EXPECT_LT(worst, 0.03) << "8-bit codes: a few % at the darkest";
  EXPECT_GT(merged.saturated_values, 0u);
}

TEST(CaptureHdrMerge, RejectsInconsistentSamples) {
  const cv::Mat a(2, 2, CV_16UC1, cv::Scalar::all(10));
  EXPECT_THROW(merge_hdr({}), InputError);
  EXPECT_THROW(merge_hdr({{a, {}, 100}, {cv::Mat(3, 2, CV_16UC1, cv::Scalar::all(0)), {}, 200}}), InputError);
  EXPECT_THROW(merge_hdr({{a, {}, 100}, {a, {}, 0}}), InputError);
  EXPECT_THROW(merge_hdr({{a, cv::Mat(1, 1, CV_16UC1, cv::Scalar::all(0)), 100}}), InputError);
  EXPECT_THROW(merge_hdr({{cv::Mat(2, 2, CV_32FC1, cv::Scalar::all(0)), {}, 100}}), InputError);
}

}  // namespace
}  // namespace lightstage
