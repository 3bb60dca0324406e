#include "lightstage/common/rig.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/testing/paths.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace lightstage {
namespace {

const char* kMinimalRig = R"(name: tiny
dome_radius_mm: 300
camera: {width: 64, height: 48}
trigger: {line: 10}
led_defaults:
  limits: {max_on_us: 1000, max_duty: 0.5}
leds:
  - {id: 0, line: 0, position_mm: [300, 0, 10]}
  - {id: 1, line: 1, position_mm: [0, 300, 10]}
  - {id: 2, line: 2, position_mm: [0, 0, 300]}
)";

// Expects parsing to fail with a message that contains every one of `needles`.
void expect_rig_error(const std::string& yaml, std::initializer_list<std::string> needles) {
  try {
    parse_rig(yaml, "broken.yaml");
    FAIL() << "no error for:\n" << yaml;
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    for (const auto& needle : needles) EXPECT_NE(message.find(needle), std::string::npos) << message;
  }
}

std::string replace(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

TEST(Rig, ParsesMinimalRig) {
  const Rig rig = parse_rig(kMinimalRig, "tiny.yaml");
  EXPECT_EQ(rig.name, "tiny");
  ASSERT_EQ(rig.leds.size(), 3u);
  EXPECT_EQ(rig.camera.width, 64);
  EXPECT_EQ(rig.camera.height, 48);
  EXPECT_EQ(rig.trigger.line.offset, 10);
  EXPECT_DOUBLE_EQ(rig.leds[1].limits.max_on_us, 1000);
  EXPECT_DOUBLE_EQ(rig.leds[1].limits.max_duty, 0.5);
  EXPECT_EQ(std::get<DirectWiring>(rig.leds[2].wiring).line.offset, 2);
  EXPECT_TRUE(rig.light_direction(rig.led(2)).isApprox(Vec3::UnitZ()));
  EXPECT_THROW(rig.led(7), InputError);
}

TEST(Rig, DefaultDomeHasAHemisphereOfLeds) {
  const Rig rig = load_rig(testing::source_dir() / "hw/rigs/sim-dome.yaml");
  EXPECT_GE(rig.leds.size(), 96u);
  EXPECT_TRUE(rig.strobe.has_value());
  double min_elevation = 90, max_elevation = 0;
  for (const Led& led : rig.leds) {
    // Every LED on the dome's sphere, above the object.
    EXPECT_NEAR((led.position_mm - rig.object_position_mm).norm(), rig.dome_radius_mm, 0.01) << led.id;
    const double elevation = deg_from_rad(std::asin(rig.light_direction(led).z()));
    min_elevation = std::min(min_elevation, elevation);
    max_elevation = std::max(max_elevation, elevation);
  }
  EXPECT_LT(min_elevation, 30);
  EXPECT_GT(max_elevation, 70);
  // Lights must span all azimuths: the mean direction points nearly straight up.
  Vec3 mean = Vec3::Zero();
  for (const Led& led : rig.leds) mean += rig.light_direction(led);
  mean /= static_cast<double>(rig.leds.size());
  EXPECT_LT(std::hypot(mean.x(), mean.y()), 0.02);
}

TEST(Rig, MatrixDomeIsWiredThroughOneChain) {
  const Rig rig = load_rig(testing::source_dir() / "hw/rigs/matrix-64.yaml");
  ASSERT_EQ(rig.leds.size(), 64u);
  ASSERT_EQ(rig.chains.size(), 1u);
  const ShiftRegisterChain& chain = rig.chains.front();
  EXPECT_EQ(chain.length, 64);
  EXPECT_EQ(chain.data.name, "SR_DATA");
  ASSERT_TRUE(chain.output_enable.has_value());
  EXPECT_TRUE(chain.output_enable->active_low);
  EXPECT_EQ(rig.camera.model, CameraModel::kPinhole);
  EXPECT_EQ(rig.camera.bit_depth, 12);
  std::vector<bool> bit_used(64, false);
  for (const Led& led : rig.leds) {
    const auto& wiring = std::get<ChainWiring>(led.wiring);
    EXPECT_EQ(wiring.chain, "leds");
    bit_used[static_cast<std::size_t>(wiring.bit)] = true;
  }
  EXPECT_EQ(std::count(bit_used.begin(), bit_used.end(), true), 64);
}

TEST(Rig, ErrorsNameFileLineAndField) {
  // Line 9 of the minimal rig holds LED 1.
  expect_rig_error(replace(kMinimalRig, "[0, 300, 10]", "[0, 300]"),
                   {"broken.yaml:9", "leds[1].position_mm", "[x, y, z]"});
  expect_rig_error(replace(kMinimalRig, "max_duty: 0.5", "max_duty: 1.5"),
                   {"broken.yaml:6", "led_defaults.limits.max_duty", "(0, 1]"});
  expect_rig_error(replace(kMinimalRig, "dome_radius_mm: 300", "dome_radius_mm: big"),
                   {"broken.yaml:2", "dome_radius_mm", "'big'"});
  expect_rig_error(replace(kMinimalRig, "dome_radius_mm: 300", "dome_radius: 300"),
                   {"broken.yaml:2", "dome_radius", "unknown key"});
  expect_rig_error(replace(kMinimalRig, "{id: 1, line: 1,", "{id: 1, line: 0,"),
                   {"broken.yaml:9", "leds[1].line", "line 0 is already used by LED 0"});
  expect_rig_error(replace(kMinimalRig, "{id: 1, line: 1,", "{id: 0, line: 1,"),
                   {"leds[1].id", "duplicate LED id 0"});
  expect_rig_error(replace(kMinimalRig, "{id: 1, line: 1,", "{id: 1, line: 10,"),
                   {"leds[1].line", "camera trigger"});
  expect_rig_error(replace(kMinimalRig, "{id: 1, line: 1,", "{id: 1,"), {"leds[1]", "exactly one"});
  expect_rig_error(replace(kMinimalRig, "{id: 1, line: 1,", "{id: 1, chain: nope, bit: 0,"),
                   {"leds[1].chain", "no chain named 'nope'"});
  expect_rig_error(replace(kMinimalRig, "name: tiny\n", ""), {"missing key 'name'"});
  expect_rig_error(replace(kMinimalRig, "  limits: {max_on_us: 1000, max_duty: 0.5}\n", "  colour: white\n"),
                   {"leds[0]", "max_on_us"});
  expect_rig_error("name: [unclosed", {"broken.yaml:1", "not valid YAML"});
  expect_rig_error("- just\n- a list\n", {"broken.yaml", "mapping"});
}

TEST(Rig, AStillsCameraTriggerHasAHalfPressLineALagAndAnArrivalTimeout) {
  const std::string dslr = replace(
      kMinimalRig, "trigger: {line: 10}",
      "trigger: {line: 10, pulse_us: 80000, focus: {line: {line: 11, active_low: true}, lead_us: 250000},\n"
      "          shutter_lag_us: 120000, arrival_timeout_us: 15000000}");
  const Rig rig = parse_rig(dslr, "dslr.yaml");
  ASSERT_TRUE(rig.trigger.focus);
  EXPECT_EQ(rig.trigger.focus->line.offset, 11);
  EXPECT_TRUE(rig.trigger.focus->line.active_low);
  EXPECT_DOUBLE_EQ(rig.trigger.focus->lead_us, 250000);
  EXPECT_DOUBLE_EQ(rig.trigger.pulse_us, 80000);
  EXPECT_DOUBLE_EQ(rig.trigger.shutter_lag_us, 120000);
  EXPECT_DOUBLE_EQ(rig.trigger.arrival_timeout_us, 15000000);
  // None of it by default: a machine-vision camera's trigger.
  const Rig plain = parse_rig(kMinimalRig, "tiny.yaml");
  EXPECT_FALSE(plain.trigger.focus);
  EXPECT_EQ(plain.trigger.shutter_lag_us, 0);
  EXPECT_EQ(plain.trigger.arrival_timeout_us, 0);

  expect_rig_error(replace(dslr, "{line: 11, active_low: true}", "1"),
                   {"leds[1].line", "line 1 is already used by the camera's focus (half-press)"});
  expect_rig_error(replace(dslr, "shutter_lag_us: 120000", "shutter_lag_us: -5"), {"trigger.shutter_lag_us"});
  expect_rig_error(replace(dslr, "lead_us: 250000", "lead: 250000"), {"trigger.focus", "lead"});
  expect_rig_error(replace(dslr, "arrival_timeout_us: 15000000", "arrival_timeout_us: 1e12"),
                   {"trigger.arrival_timeout_us", "one hour"});
}

TEST(Rig, ChainBitsAreCheckedAgainstTheChain) {
  const std::string chained = replace(kMinimalRig, "leds:\n",
                                      "chains:\n"
                                      "  - {name: c, data: 20, clock: 21, latch: 22, length: 8}\n"
                                      "leds:\n");
  const Rig rig = parse_rig(replace(chained, "{id: 1, line: 1,", "{id: 1, chain: c, bit: 7,"), "c.yaml");
  EXPECT_EQ(std::get<ChainWiring>(rig.led(1).wiring).bit, 7);
  expect_rig_error(replace(chained, "{id: 1, line: 1,", "{id: 1, chain: c, bit: 8,"),
                   {"leds[1].bit", "outside chain 'c' of length 8"});
  expect_rig_error(replace(chained, "clock: 21", "clock: 20"), {"chains[0]", "line 20", "data"});
}

TEST(Rig, DuplicateKeysAreRefusedWithBothLines) {
  // A second, tighter limit must not be silently ignored (yaml-cpp's lookups find the first).
  expect_rig_error(replace(kMinimalRig, "max_duty: 0.5}", "max_duty: 0.5, max_on_us: 10}"),
                   {"broken.yaml:6", "duplicate key 'led_defaults.limits.max_on_us'", "first at line 6"});
  expect_rig_error(
      replace(kMinimalRig, "trigger: {line: 10}\n", "trigger: {line: 10}\ndome_radius_mm: 200\n"),
      {"broken.yaml:5", "duplicate key 'dome_radius_mm'", "first at line 2"});
  expect_rig_error(replace(kMinimalRig, "{id: 1, line: 1,", "{id: 1, line: 1, line: 7,"),
                   {"broken.yaml:9", "duplicate key 'leds[1].line'", "first at line 9"});
  expect_rig_error(replace(kMinimalRig, "  limits: {max_on_us: 1000, max_duty: 0.5}\n",
                           "  limits:\n    max_on_us: 1000\n    max_duty: 0.5\n    max_on_us: 10\n"),
                   {"broken.yaml:9", "led_defaults.limits.max_on_us", "first at line 7"});
  // The same key in different mappings is no duplicate.
  EXPECT_NO_THROW(parse_rig(replace(kMinimalRig, "{id: 1, line: 1,", "{id: 1, line: {line: 1},"), "ok.yaml"));
}

TEST(Rig, DurationsAreRangeChecked) {
  // 1e30 us would overflow the firmware's int64 nanoseconds.
  expect_rig_error(replace(kMinimalRig, "max_on_us: 1000", "max_on_us: 1e30"),
                   {"broken.yaml:6", "led_defaults.limits.max_on_us", "at most 3600000000 us", "1e30"});
  expect_rig_error(
      replace(kMinimalRig, "trigger: {line: 10}", "trigger: {line: 10, pulse_us: 99999999999999}"),
      {"broken.yaml:4", "trigger.pulse_us", "at most"});
  expect_rig_error(
      replace(kMinimalRig, "trigger: {line: 10}", "trigger: {line: 10}\nstrobe: {line: 11, timeout_us: 4e9}"),
      {"strobe.timeout_us", "at most"});
  expect_rig_error(replace(kMinimalRig, "max_duty: 0.5}", "max_duty: 0.5, duty_window_us: 1e12}"),
                   {"led_defaults.limits.duty_window_us", "at most"});
  expect_rig_error(replace(kMinimalRig, "height: 48}", "height: 48, exposure_us: 1e19}"),
                   {"camera.exposure_us", "at most"});
  expect_rig_error(replace(kMinimalRig, "leds:\n",
                           "chains:\n  - {name: c, data: 20, clock: 21, latch: 22, length: 8, "
                           "clock_period_us: 1e300}\nleds:\n"),
                   {"chains[0].clock_period_us", "at most"});
  const Rig longest = parse_rig(replace(kMinimalRig, "max_on_us: 1000", "max_on_us: 3600000000"), "ok.yaml");
  EXPECT_DOUBLE_EQ(longest.leds[0].limits.max_on_us, kMaxRigDurationUs);
  // The firmware converts with llround(us * 1000): the cap must stay far inside int64.
  EXPECT_LT(kMaxRigDurationUs * 1000.0, 1e18);
}

TEST(Rig, QuotedValuesAreEscapedAndCut) {
  const std::string huge(100000, 'x');
  try {
    parse_rig(replace(kMinimalRig, "dome_radius_mm: 300", "dome_radius_mm: " + huge), "broken.yaml");
    FAIL();
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_LT(message.size(), 300u) << message.size();
    EXPECT_NE(message.find("xxx..."), std::string::npos) << message;
  }
  // A terminal escape in the rig name is refused, and shown escaped, not raw.
  try {
    parse_rig(replace(kMinimalRig, "name: tiny", "name: \"ti\\e[2Jny\""), "broken.yaml");
    FAIL();
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.find('\x1b'), std::string::npos) << message;
    EXPECT_NE(message.find("ti\\x1b[2Jny"), std::string::npos) << message;
    EXPECT_NE(message.find("control characters"), std::string::npos) << message;
  }
}

TEST(Rig, MissingFileIsNamed) {
  try {
    load_rig("/nonexistent/rig.yaml");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/rig.yaml"), std::string::npos);
  }
}

}  // namespace
}  // namespace lightstage
