#include "lightstage/host/radiometry.hpp"

#include "lightstage/common/error.hpp"

#include <gtest/gtest.h>

namespace lightstage {
namespace {

constexpr double kR = 0.2989, kG = 0.5870, kB = 0.1140;

ImageStack colour_stack() {
  ImageStack stack;
  for (int i = 0; i < 3; ++i) {
    Frame frame;
    frame.filename = "f" + std::to_string(i);
    frame.image = cv::Mat(2, 3, CV_16UC3, cv::Scalar::all(0));
    frame.light_direction = Vec3(i == 0 ? 2.0 : 0.0, i == 1 ? 2.0 : 0.0, 1.0);  // not unit on purpose
    frame.light_intensity = Vec3(2.0, 4.0, 8.0);
    stack.frames.push_back(frame);
  }
  return stack;
}

TEST(HostRadiometry, ColourIsNormalisedPerChannelThenGreyBt601InBgrOrder) {
  ImageStack stack = colour_stack();
  // Pixel (x=1, y=0): B=6553.5-ish, only red at (x=2, y=1).
  stack.frames[0].image.at<cv::Vec3w>(0, 1) = cv::Vec3w(1000, 2000, 3000);  // B, G, R
  stack.frames[0].image.at<cv::Vec3w>(1, 2) = cv::Vec3w(0, 0, 65535);
  const Observations obs = make_observations(stack);
  ASSERT_EQ(obs.pixel_count(), 6u);  // no mask: every pixel, row-major
  EXPECT_EQ(obs.pixels[1], cv::Point(1, 0));
  EXPECT_EQ(obs.pixels[5], cv::Point(2, 1));
  const double expected = kR * 3000 / 65535.0 / 2.0 + kG * 2000 / 65535.0 / 4.0 + kB * 1000 / 65535.0 / 8.0;
  EXPECT_NEAR(obs.intensities(1, 0), expected, 1e-7);
  EXPECT_NEAR(obs.intensities(5, 0), kR / 2.0, 1e-7);  // red holds R, divided by the red intensity
  EXPECT_TRUE(obs.saturated(5, 0));
  EXPECT_FALSE(obs.saturated(1, 0));
  EXPECT_EQ(obs.intensities(0, 1), 0.0f);
  // Lights are unit.
  EXPECT_NEAR(obs.lights.row(0).norm(), 1.0, 1e-12);
  EXPECT_NEAR(obs.lights(0, 0), 2.0 / std::sqrt(5.0), 1e-12);
}

TEST(HostRadiometry, ClampsToOneUnlessAskedNot) {
  ImageStack stack = colour_stack();
  for (auto& frame : stack.frames) frame.light_intensity = Vec3(0.25, 0.25, 0.25);
  stack.frames[1].image.at<cv::Vec3w>(0, 0) = cv::Vec3w(40000, 40000, 40000);
  EXPECT_EQ(make_observations(stack).intensities(0, 1), 1.0f);
  RadiometryOptions options;
  options.clamp_to_one = false;
  EXPECT_NEAR(make_observations(stack, options).intensities(0, 1), (kR + kG + kB) * 40000 / 65535.0 / 0.25,
              1e-5);
}

TEST(HostRadiometry, GreyEightBitWithBlackLevelSaturationAndMask) {
  ImageStack stack;
  for (int i = 0; i < 3; ++i) {
    Frame frame;
    frame.image = cv::Mat(3, 3, CV_8UC1, cv::Scalar::all(100));
    frame.black_level = 10;
    frame.saturation_level = 200;
    frame.light_intensity = Vec3(2, 2, 2);
    frame.light_direction = Vec3(0, 0, 1);
    stack.frames.push_back(frame);
  }
  stack.frames[2].image.at<std::uint8_t>(1, 1) = 200;
  stack.mask = cv::Mat(3, 3, CV_8UC1, cv::Scalar::all(0));
  stack.mask.at<std::uint8_t>(1, 1) = 255;
  stack.mask.at<std::uint8_t>(2, 0) = 1;  // any nonzero is inside
  const Observations obs = make_observations(stack);
  ASSERT_EQ(obs.pixel_count(), 2u);
  EXPECT_EQ(obs.pixels[0], cv::Point(1, 1));
  EXPECT_EQ(obs.pixels[1], cv::Point(0, 2));
  EXPECT_EQ(obs.mask.at<std::uint8_t>(2, 0), 255);
  // Grey images divide by the grey of the intensity, with the BT.601 weights
  // normalised to sum to 1: a grey light of 2 divides by exactly 2.
  EXPECT_NEAR(obs.intensities(0, 0), 90 / 255.0 / 2, 1e-6);
  EXPECT_TRUE(obs.saturated(0, 2));
  EXPECT_FALSE(obs.saturated(0, 1));
  EXPECT_FALSE(obs.saturated(1, 2));
}

TEST(HostRadiometry, RejectsInconsistentStacks) {
  ImageStack stack = colour_stack();
  stack.frames[2].image = cv::Mat(2, 3, CV_8UC3, cv::Scalar::all(0));
  EXPECT_THROW(make_observations(stack), InputError);
  stack = colour_stack();
  stack.mask = cv::Mat(5, 5, CV_8UC1, cv::Scalar::all(255));
  EXPECT_THROW(make_observations(stack), InputError);
  EXPECT_THROW(make_observations(ImageStack{}), InputError);
}

}  // namespace
}  // namespace lightstage
