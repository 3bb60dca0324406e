#include "lightstage/host/capture/response_curve.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/sim/sensor.hpp"
#include "lightstage/testing/paths.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>

namespace lightstage {
namespace {

// A still scene (radiance spread over two decades) seen at several exposures
// through a gamma-encoding camera: DN = full · (radiance · t / t_ref)^(1/γ).
std::vector<cv::Mat> bracket(const std::vector<double>& exposures_us, double gamma, int bits,
                             cv::Mat* radiance_out) {
  cv::Mat radiance(64, 64, CV_64FC1);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> log_r(std::log(0.01), std::log(1.0));
  for (auto it = radiance.begin<double>(); it != radiance.end<double>(); ++it) *it = std::exp(log_r(rng));
  if (radiance_out) *radiance_out = radiance;
  const double full = std::ldexp(1.0, bits) - 1;
  std::vector<cv::Mat> images;
  for (const double t : exposures_us) {
    cv::Mat dn(radiance.size(), CV_16UC1);
    for (int r = 0; r < dn.rows; ++r) {
      for (int c = 0; c < dn.cols; ++c) {
        const double y = std::min(1.0, radiance.at<double>(r, c) * t / 8000.0);
        dn.at<std::uint16_t>(r, c) = static_cast<std::uint16_t>(std::lround(full * std::pow(y, 1 / gamma)));
      }
    }
    images.push_back(dn);
  }
  return images;
}

TEST(ResponseCurve, AGammaCameraIsLinearWithinOnePercentAfterCalibration) {
  const std::vector<double> exposures = {500, 1000, 2000, 4000, 8000, 16000};
  const auto images = bracket(exposures, 2.2, 16, nullptr);
  // The check uses the middle of the bracket, where many pixels are well exposed in every frame.
  const std::vector<double> middle(exposures.begin() + 2, exposures.begin() + 5);
  const std::vector<cv::Mat> middle_images(images.begin() + 2, images.begin() + 5);
  // Uncorrected, the data is far from linear...
  const LinearityReport raw = check_linearity(middle_images, middle, InverseResponse::identity(16));
  EXPECT_GT(raw.max_deviation, 0.2);
  // ...calibrated, it is linear within 1% over the range used.
  const InverseResponse response = calibrate_response(images, exposures, 16);
  const LinearityReport fixed = check_linearity(middle_images, middle, response);
  EXPECT_LT(fixed.max_deviation, 0.01) << fixed.to_json().dump();
  EXPECT_GT(fixed.pixels_used, 100u);
  // The curve found is the gamma curve, up to the scale no bracket can tell.
  for (const double v : {0.2, 0.35, 0.8}) {
    EXPECT_NEAR(response.at(v * 65535) / response.at(0.5 * 65535), std::pow(v / 0.5, 2.2),
                0.01 * std::pow(v / 0.5, 2.2))
        << v;
  }
}

TEST(ResponseCurve, LinearDataStaysLinear) {
  const std::vector<double> exposures = {1000, 2000, 4000, 8000};
  const auto images = bracket(exposures, 1.0, 16, nullptr);
  EXPECT_LT(check_linearity(images, exposures, InverseResponse::identity(16)).max_deviation, 0.005);
}

TEST(ResponseCurve, SavedAndLoadedUnchanged) {
  const InverseResponse r(12, {0, 0.1, 0.3, 1.0});
  const auto file = testing::scratch_dir() / "response.json";
  r.save(file);
  const InverseResponse back = InverseResponse::load(file);
  EXPECT_EQ(back.bits(), 12);
  EXPECT_EQ(back.knots(), r.knots());
  EXPECT_DOUBLE_EQ(back.at(4095.0 / 3), 0.1);
  cv::Mat image(1, 2, CV_16UC1);
  image.at<std::uint16_t>(0, 0) = 0;
  image.at<std::uint16_t>(0, 1) = 4095;
  const cv::Mat lin = back.linearise(image);
  EXPECT_FLOAT_EQ(lin.at<float>(0, 0), 0.0f);
  EXPECT_FLOAT_EQ(lin.at<float>(0, 1), 1.0f);
}

TEST(ResponseCurve, BadFilesAndBracketsAreNamed) {
  const auto file = testing::scratch_dir() / "bad.json";
  std::ofstream(file)
      << R"({"format": "lightstage-response", "version": 1, "bits": 16, "knots": [0, 0.5, 0.2]})";
  try {
    InverseResponse::load(file);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.json"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("decrease"), std::string::npos) << e.what();
  }
  std::ofstream(file, std::ios::trunc)
      << R"({"format": "lightstage-response", "version": 1, "bits": 16, "knots": [0, "x"]})";
  EXPECT_THROW(InverseResponse::load(file), InputError);
  const std::vector<double> two = {1000, 2000};
  EXPECT_THROW(calibrate_response(bracket(two, 2.2, 16, nullptr), two, 16), InputError);
}

// A still scene through the simulator's camera (noise, quantisation, a gamma
// 2.2 response) at each exposure: a bracket whose true response is known.
std::vector<cv::Mat> simulated_bracket(const std::vector<double>& exposures_us,
                                       const CameraDefaults& camera) {
  cv::Mat shading(96, 96, CV_64FC1);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> log_s(std::log(0.003), std::log(1.2));
  for (auto it = shading.begin<double>(); it != shading.end<double>(); ++it) *it = std::exp(log_s(rng));
  std::vector<cv::Mat> images;
  for (std::size_t i = 0; i < exposures_us.size(); ++i) {
    sim::SensorOptions options;
    options.exposure_us = exposures_us[i];
    options.response = sim::ResponseCurve::parse("gamma:2.2");
    images.push_back(sim::Sensor(options, camera).expose(shading, 5, i));
  }
  return images;
}

TEST(ResponseCurve, TheFitFollowsTheSimulatorsResponseToBothEnds) {
  CameraDefaults camera;
  const std::vector<double> exposures = response_bracket_us(camera.exposure_us);
  ASSERT_EQ(exposures.size(), 8u);
  const InverseResponse response = calibrate_response(simulated_bracket(exposures, camera), exposures, 16);
  // Radiance at full scale is 1 for both; below, the fit must be the gamma curve.
  for (const double v : {0.02, 0.04, 0.08, 0.15, 0.3, 0.5, 0.7, 0.85, 0.95, 0.98}) {
    const double truth = std::pow(v, 2.2);
    EXPECT_NEAR(response.at(v * 65535), truth, 0.06 * truth) << "at " << v << " of full scale";
  }
}

TEST(ResponseCurve, TheDefaultLinearityBracketChecksAFittedCamera) {
  CameraDefaults camera;
  const std::vector<double> wide = response_bracket_us(camera.exposure_us);
  const InverseResponse response = calibrate_response(simulated_bracket(wide, camera), wide, 16);
  const std::vector<double> exposures = linearity_bracket_us(camera.exposure_us);
  const auto images = simulated_bracket(exposures, camera);
  EXPECT_GT(check_linearity(images, exposures, InverseResponse::identity(16)).max_deviation, 0.1);
  const LinearityReport report = check_linearity(images, exposures, response);
  EXPECT_GT(report.pixels_used, 500u);
  EXPECT_LT(report.max_deviation, 0.02) << report.to_json().dump();
}

}  // namespace
}  // namespace lightstage
