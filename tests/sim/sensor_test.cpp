#include "lightstage/sim/sensor.hpp"
#include "lightstage/common/error.hpp"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <cmath>

namespace lightstage::sim {
namespace {

SensorOptions noiseless() {
  SensorOptions o;
  o.noise = NoiseModel::kNone;
  return o;
}

// A ramp of shading values from 0 to 1.2 (past saturation).
cv::Mat ramp() {
  cv::Mat s(16, 64, CV_64FC1);
  for (int r = 0; r < s.rows; ++r) {
    for (int c = 0; c < s.cols; ++c) s.at<double>(r, c) = 1.2 * (r * s.cols + c) / (s.total() - 1.0);
  }
  return s;
}

TEST(SimSensor, NoiselessQuantisationIsExact) {
  SensorOptions o = noiseless();
  o.black_level = 64;
  const Sensor sensor(o, CameraDefaults{});
  const cv::Mat s = ramp();
  const cv::Mat dn = sensor.expose(s, 1, 0);
  ASSERT_EQ(dn.type(), CV_16UC1);
  for (int r = 0; r < s.rows; ++r) {
    for (int c = 0; c < s.cols; ++c) {
      const double expected =
          std::min(65535.0, std::nearbyint(64 + std::min(s.at<double>(r, c) * 0.8, 1.0) * 65535));
      ASSERT_EQ(dn.at<std::uint16_t>(r, c), expected) << r << "," << c;
    }
  }
  EXPECT_DOUBLE_EQ(sensor.dn_per_shading(), 0.8 * 65535);
}

TEST(SimSensor, TwelveBitCodesScaledOrNot) {
  SensorOptions o = noiseless();
  o.bit_depth = 12;
  const cv::Mat s = ramp();
  const Sensor scaled(o, CameraDefaults{});
  EXPECT_DOUBLE_EQ(scaled.saturation_level(), 4095.0 * 16);
  const cv::Mat a = scaled.expose(s, 1, 0);
  o.scale_to_16bit = false;
  const Sensor raw(o, CameraDefaults{});
  EXPECT_DOUBLE_EQ(raw.saturation_level(), 4095.0);
  const cv::Mat b = raw.expose(s, 1, 0);
  for (int i = 0; i < static_cast<int>(s.total()); ++i) {
    const int va = a.at<std::uint16_t>(i), vb = b.at<std::uint16_t>(i);
    ASSERT_EQ(va % 16, 0);
    ASSERT_EQ(va, vb * 16);
    ASSERT_EQ(vb, std::nearbyint(std::min(s.at<double>(i) * 0.8, 1.0) * 4095));
  }
}

TEST(SimSensor, SaturationClips) {
  SensorOptions o = noiseless();
  o.black_level = 1000;
  const Sensor sensor(o, CameraDefaults{});
  cv::Mat s(4, 4, CV_64FC1, cv::Scalar(5.0));
  s.at<double>(0, 0) = 1.24;  // y = 0.992: black + y·65535 exceeds the range
  s.at<double>(0, 1) = std::numeric_limits<double>::quiet_NaN();
  const cv::Mat dn = sensor.expose(s, 1, 0);
  EXPECT_EQ(dn.at<std::uint16_t>(0, 0), 65535);
  EXPECT_EQ(dn.at<std::uint16_t>(0, 1), 1000);  // NaN renders as black
  EXPECT_EQ(dn.at<std::uint16_t>(3, 3), 65535);
  // Physical noise saturates at the full well too.
  SensorOptions p;
  const Sensor physical(p, CameraDefaults{});
  const cv::Mat dp = physical.expose(s, 1, 0);
  EXPECT_EQ(dp.at<std::uint16_t>(3, 3), 65535);
}

TEST(SimSensor, ExposureAndGainScaleTheSignal) {
  SensorOptions o = noiseless();
  CameraDefaults cam;
  cam.exposure_us = 1000;
  o.exposure_us = 500;
  o.gain = 1.5;
  const Sensor sensor(o, cam);
  EXPECT_DOUBLE_EQ(sensor.dn_per_shading(), 0.8 * 0.5 * 1.5 * 65535);
}

// Below the rig's gain the well fills before the ADC does: bright pixels stop
// at a code under full scale, and saturation_level() reports that code.
TEST(SimSensor, LowGainSaturatesBelowFullScale) {
  SensorOptions o = noiseless();
  o.gain = 0.5;
  const Sensor sensor(o, CameraDefaults{});
  EXPECT_DOUBLE_EQ(sensor.saturation_level(), std::nearbyint(0.5 * 65535));
  cv::Mat s(2, 2, CV_64FC1, cv::Scalar(10.0));
  s.at<double>(0, 0) = 0.5;  // y = 0.2, well below the well
  const cv::Mat dn = sensor.expose(s, 1, 0);
  EXPECT_EQ(dn.at<std::uint16_t>(1, 1), sensor.saturation_level());
  EXPECT_LT(sensor.saturation_level(), 65535);
  EXPECT_EQ(dn.at<std::uint16_t>(0, 0), std::nearbyint(0.5 * 0.8 * 0.5 * 65535));
}

double stddev(const cv::Mat& dn) {
  cv::Scalar mean, sd;
  cv::meanStdDev(dn, mean, sd);
  return sd[0];
}

TEST(SimSensor, PhysicalNoiseMatchesTheModel) {
  SensorOptions o;
  o.noise = NoiseModel::kPhysical;
  o.full_well_e = 20000;
  o.read_noise_e = 10;
  const Sensor sensor(o, CameraDefaults{});
  const cv::Mat s(128, 128, CV_64FC1, cv::Scalar(0.5));
  const double electrons = 0.5 * 0.8 * 20000;
  const double expected = std::sqrt(electrons + 100) / 20000 * 65535;
  EXPECT_NEAR(stddev(sensor.expose(s, 4, 2)), expected, 0.03 * expected);
}

TEST(SimSensor, SignalDependentNoiseMatchesTheModel) {
  SensorOptions o;
  o.noise = NoiseModel::kSignalDependent;
  o.lambda = 0.05;
  const Sensor sensor(o, CameraDefaults{});
  const cv::Mat s(128, 128, CV_64FC1, cv::Scalar(0.5));
  const double expected = 0.05 * 0.4 * 65535;
  const cv::Mat dn = sensor.expose(s, 4, 2);
  EXPECT_NEAR(stddev(dn), expected, 0.03 * expected);
  EXPECT_NEAR(cv::mean(dn)[0], 0.4 * 65535, 0.01 * 0.4 * 65535);
}

TEST(SimSensor, SeedsDecideTheNoise) {
  const Sensor sensor(SensorOptions{}, CameraDefaults{});
  const cv::Mat s(32, 32, CV_64FC1, cv::Scalar(0.3));
  const cv::Mat a = sensor.expose(s, 11, 5);
  EXPECT_EQ(cv::norm(a, sensor.expose(s, 11, 5), cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(a, sensor.expose(s, 12, 5), cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(a, sensor.expose(s, 11, 6), cv::NORM_INF), 0.0);
}

TEST(SimSensor, ResponseCurvesAreMonotoneWithFixedEnds) {
  for (const char* text : {"identity", "gamma:2.2", "gamma:0.5", "srgb", "s-curve:2", "s-curve:0.7"}) {
    const ResponseCurve curve = ResponseCurve::parse(text);
    EXPECT_DOUBLE_EQ(curve.apply(0.0), 0.0) << text;
    EXPECT_NEAR(curve.apply(1.0), 1.0, 1e-12) << text;
    double previous = 0;
    for (int i = 1; i <= 1000; ++i) {
      const double y = curve.apply(i / 1000.0);
      ASSERT_GT(y, previous) << text << " at " << i;
      previous = y;
    }
  }
  EXPECT_NEAR(ResponseCurve::parse("gamma:2.2").apply(0.5), std::pow(0.5, 1 / 2.2), 1e-15);
  EXPECT_THROW(ResponseCurve::parse("gamma:-1"), InputError);
  EXPECT_THROW(ResponseCurve::parse("log"), InputError);
}

TEST(SimSensor, CheckNamesTheField) {
  SensorOptions o;
  o.exposure_us = -5;
  try {
    o.check();
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("exposure_us"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("-5"), std::string::npos) << e.what();
  }
  SensorOptions b;
  b.bit_depth = 20;
  EXPECT_THROW(b.check(), InputError);
}

}  // namespace
}  // namespace lightstage::sim
