#include "lightstage/firmware/led_safety.hpp"

#include <gtest/gtest.h>

namespace lightstage::firmware {
namespace {

Rig two_led_rig() {
  return parse_rig(R"(name: t
dome_radius_mm: 300
camera: {width: 8, height: 8}
trigger: {line: 9}
led_defaults:
  limits: {max_on_us: 1000, max_duty: 0.25, duty_window_us: 8000}
leds:
  - {id: 3, line: 0, position_mm: [0, 0, 300]}
  - {id: 4, line: 1, position_mm: [300, 0, 0], limits: {max_on_us: 50}}
)",
                   "t.yaml");
}

TEST(LedSafety, RefusesPulsesLongerThanTheOnTimeLimit) {
  const LedSafety safety(two_led_rig());
  EXPECT_TRUE(safety.check(3, 0, 1000).allowed);
  const SafetyVerdict verdict = safety.check(3, 0, 1001);
  EXPECT_FALSE(verdict.allowed);
  EXPECT_NE(verdict.reason.find("max_on_us"), std::string::npos) << verdict.reason;
  // Per-LED limits override the defaults.
  EXPECT_FALSE(safety.check(4, 0, 51).allowed);
  EXPECT_FALSE(safety.check(99, 0, 1).allowed);
  EXPECT_FALSE(safety.check(3, 0, -1).allowed);
}

TEST(LedSafety, EnforcesDutyCycleOverASlidingWindow) {
  LedSafety safety(two_led_rig());
  // Budget: 0.25 * 8000 = 2000 us in any 8000 us window.
  safety.record(3, 0, 1000);
  EXPECT_TRUE(safety.check(3, 1500, 1000).allowed);  // exactly 2000 us in the window
  safety.record(3, 1500, 2500);
  EXPECT_DOUBLE_EQ(safety.on_time_in_window(3, 2500), 2000);
  EXPECT_FALSE(safety.check(3, 3000, 100).allowed);
  // Once the first pulse leaves the window, there is room again.
  EXPECT_TRUE(safety.check(3, 8500, 500).allowed);
  EXPECT_FALSE(safety.check(3, 7000, 1000).allowed);  // window (0, 8000] already holds 2000 us
  EXPECT_TRUE(safety.check(3, 10600, 1000).allowed);
  // Other LEDs are accounted separately.
  EXPECT_TRUE(safety.check(4, 3000, 50).allowed);
}

}  // namespace
}  // namespace lightstage::firmware
