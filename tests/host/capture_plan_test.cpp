// The capture planner: which LEDs, at which exposures, darks at which; no device involved.
#include "lightstage/host/capture/capture_plan.hpp"

#include "lightstage/testing/errors.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace lightstage {
namespace {

using testing::error_of;

Rig three_led_rig() {
  Rig rig;
  rig.name = "plan-test";
  for (const int id : {4, 5, 6}) {
    Led led;
    led.id = id;
    led.position_mm = Vec3(100.0 * id, 0, 300);
    led.limits.max_on_us = 2'000'000;
    rig.leds.push_back(led);
  }
  rig.camera.exposure_us = 8000;
  return rig;
}

TEST(CapturePlan, LedsAreTheRigsInOrderOrTheOnesAskedFor) {
  const Rig rig = three_led_rig();
  EXPECT_EQ(plan_led_ids(rig, {}), (std::vector<int>{4, 5, 6}));
  EXPECT_EQ(plan_led_ids(rig, {6, 4}), (std::vector<int>{6, 4}));
  EXPECT_THROW(plan_led_ids(rig, {4, 9}), InputError);
}

TEST(CapturePlan, LedsOfOneExposureShareItsIndexAndItsDark) {
  const CapturePlan plan = make_plan({4, 5, 6}, {{4, 2000}, {5, 500}, {6, 2000}}, {}, {}, 4);
  EXPECT_FALSE(plan.hdr());
  EXPECT_EQ(plan.exposures_us, (std::vector<double>{500, 2000}));
  ASSERT_EQ(plan.frames.size(), 3u);
  EXPECT_EQ(plan.led_ids(), (std::vector<int>{4, 5, 6}));
  EXPECT_EQ(plan.frames[0].exposure, 1u);
  EXPECT_EQ(plan.frames[1].exposure, 0u);
  EXPECT_EQ(plan.frames[2].exposure, 1u);
  EXPECT_DOUBLE_EQ(plan.exposure_us(1), 500);
  EXPECT_TRUE(plan.frames[0].bracket.empty());
  EXPECT_EQ(plan.taken_exposures(), (std::vector<std::size_t>{0, 1}));
  EXPECT_EQ(plan.dark_frames, 4);
}

TEST(CapturePlan, WithABracketDarksAreTakenAtTheBracketExposuresOnly) {
  const CapturePlan plan =
      make_plan({4, 5}, {{4, 1000}, {5, 3000}}, {{4, {125, 1000}}, {5, {375, 1000}}}, {-3, 0}, 2);
  EXPECT_TRUE(plan.hdr());
  EXPECT_EQ(plan.exposures_us, (std::vector<double>{125, 375, 1000, 3000}));
  EXPECT_EQ(plan.frames[0].exposure, 2u);
  EXPECT_EQ(plan.frames[0].bracket, (std::vector<std::size_t>{0, 2}));
  EXPECT_EQ(plan.frames[1].exposure, 3u);
  EXPECT_EQ(plan.frames[1].bracket, (std::vector<std::size_t>{1, 2}));
  // 3000 us is LED 5's base exposure, but no camera frame is taken at it.
  EXPECT_EQ(plan.taken_exposures(), (std::vector<std::size_t>{0, 1, 2}));
}

TEST(CapturePlan, APlanThatDoesNotFitIsRefusedNamingTheLed) {
  EXPECT_NE(error_of([] {
              make_plan({4, 5}, {{4, 1000}}, {}, {}, 0);
            }).find("LED 5 has no exposure"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              make_plan({4}, {{4, 1000}}, {}, {0, -3}, 0);
            }).find("LED 4 has no bracket"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              make_plan({4}, {{4, -1}}, {}, {}, 0);
            }).find("not a positive number"),
            std::string::npos);
  // A bracket listed longest first (a hand-edited manifest) is not taken as it stands.
  EXPECT_NE(error_of([] {
              make_plan({4}, {{4, 1000}}, {{4, {1000, 125}}}, {0, -3}, 0);
            }).find("LED 4"),
            std::string::npos);
  CapturePlan plan = make_plan({4}, {{4, 1000}}, {}, {}, 0);
  plan.frames[0].exposure = 3;
  EXPECT_NE(error_of([&] { plan.check(); }).find("frame 1 (LED 4) has no exposure"), std::string::npos);
}

TEST(CapturePlan, BracketsAreWholeMicrosecondsWithinTheCameraAndTheLedShortestFirst) {
  const Rig rig = three_led_rig();
  camera::ControlInfo range;
  range.exposure_min_us = 100;
  range.exposure_max_us = 50'000;
  EXPECT_EQ(bracket_exposures(rig.led(4), 1000, {0, -3, -6}, range, 500),
            (std::vector<double>{100, 125, 1000}));  // 1000/64 is below the camera's shortest
  EXPECT_EQ(bracket_exposures(rig.led(4), 1000, {-1.5, 6}, range, 500), (std::vector<double>{354, 50'000}));
  EXPECT_EQ(bracket_exposures(rig.led(4), 1000, {-4, -5}, range, 500), (std::vector<double>{100}));
}

TEST(CapturePlan, TheLongestExposureKeepsTheLedWithinItsOnTime) {
  Rig rig = three_led_rig();
  camera::ControlInfo range;  // no camera limit
  EXPECT_DOUBLE_EQ(longest_exposure_us(rig.led(4), range, 500), (2'000'000 - 800) / 1.05);
  range.exposure_max_us = 30'000;
  EXPECT_DOUBLE_EQ(longest_exposure_us(rig.led(4), range, 500), 30'000);
}

// A preview whose values are `level` everywhere, 12-bit.
camera::Frame flat_frame(double level) {
  camera::Frame frame;
  frame.bit_depth = 12;
  frame.image = cv::Mat(4, 4, CV_16UC1, cv::Scalar(level));
  return frame;
}

TEST(CapturePlan, AutomaticExposureAimsThePreviewAtTheTargetAndRetriesClippedOnesShorter) {
  const Rig rig = three_led_rig();
  camera::ControlInfo range;
  range.exposure_min_us = 10;
  range.exposure_max_us = 100'000;
  CaptureOptions options;
  options.auto_target = 0.5;
  std::vector<std::pair<std::vector<int>, double>> asked;
  const auto preview = [&](const std::vector<int>& ids, double exposure_us) {
    asked.emplace_back(ids, exposure_us);
    std::vector<camera::Frame> frames;
    for (const int id : ids) {
      // LED 4 is a quarter of full scale at 8 ms; LED 5 clips until 1 ms; LED 6 always clips.
      const double level = id == 4 ? 1024 : id == 5 ? (exposure_us > 1000 ? 4095 : 2048) : 4095;
      frames.push_back(flat_frame(level));
    }
    return frames;
  };
  const std::map<int, double> exposure = auto_exposures(rig, {4, 5, 6}, range, options, preview);
  ASSERT_EQ(asked.size(), 6u);
  EXPECT_EQ(asked[0].first, (std::vector<int>{4, 5, 6}));
  EXPECT_DOUBLE_EQ(asked[0].second, 8000);  // the rig camera's
  EXPECT_EQ(asked[1].first, (std::vector<int>{5, 6}));
  EXPECT_DOUBLE_EQ(asked[1].second, 1000);  // 3 stops shorter
  EXPECT_EQ(asked[2].first, (std::vector<int>{6}));
  // 0.5 * 4095 / 1024 of 8 ms is just under 16 ms: on the 1/6-stop grid from 8 ms, 16 ms.
  EXPECT_DOUBLE_EQ(exposure.at(4), 16'000);
  EXPECT_DOUBLE_EQ(exposure.at(5), 1000);  // 0.5 * 4095 / 2048 of 1 ms, on the grid
  // Still clipped after 6 rounds: the next preview's exposure, at least the camera's shortest.
  EXPECT_DOUBLE_EQ(exposure.at(6), std::max(10.0, 8000 / std::pow(8, 6)));
}

TEST(CapturePlan, AStrobeTimeoutFitsTheLedsOnTimeLimit) {
  // Room for a late camera when the limit allows...
  EXPECT_EQ(strobe_timeout_us(10'000, 2'000'000, 500), 210'000u);
  // ...but never more than the limit leaves after the settle time (the controller counts all of it).
  EXPECT_EQ(strobe_timeout_us(1'800'000, 2'000'000, 500), 1'999'500u);
  EXPECT_GE(strobe_timeout_us(1'800'000, 2'000'000, 500), open_loop_on_us(1'800'000));
  // Darks light nothing: no limit.
  EXPECT_EQ(strobe_timeout_us(1'800'000, 0, 500), 2'000'000u);
}

TEST(CapturePlan, AnExposureTooLongForAnLedIsRefusedBeforeAnythingIsTaken) {
  const Rig rig = three_led_rig();
  const OnTimeLimits limits = {{4, 2'000'000}, {5, 2'000'000}, {6, 100'000}};
  const CapturePlan fits = make_plan({4, 5}, {{4, 1'900'000}, {5, 1000}}, {}, {}, 2);
  EXPECT_NO_THROW(check_on_time(fits, limits, 500));
  // The longest exposure the planner allows an LED fits its limit exactly.
  const camera::ControlInfo range;
  const double longest = longest_exposure_us(rig.led(4), range, 500);
  EXPECT_NO_THROW(check_on_time(make_plan({4}, {{4, longest}}, {}, {}, 0), limits, 500));

  const std::string message = error_of([&] {
    check_on_time(make_plan({4, 6}, {{4, 1000}, {6, 200'000}}, {}, {}, 2), limits, 500);
  });
  EXPECT_NE(message.find("LED 6 at 200000 us"), std::string::npos) << message;
  EXPECT_NE(message.find("max_on_us 100000"), std::string::npos) << message;
  // A bracket's longest exposure counts.
  EXPECT_NE(error_of([&] {
              check_on_time(make_plan({6}, {{6, 50'000}}, {{6, {50'000, 200'000}}}, {0, 2}, 0), limits, 500);
            }).find("LED 6 at 200000 us"),
            std::string::npos);
}

}  // namespace
}  // namespace lightstage
