#include "lightstage/common/rig_fingerprint.hpp"

#include "lightstage/testing/paths.hpp"

#include <gtest/gtest.h>

#include <string>

namespace lightstage {
namespace {

const char* kRig = R"(name: tiny
description: three LEDs
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

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

std::string fingerprint_of(const std::string& yaml) { return rig_fingerprint(parse_rig(yaml, "rig.yaml")); }

TEST(RigFingerprint, IsSixteenHexDigitsAndStable) {
  const std::string fingerprint = fingerprint_of(kRig);
  EXPECT_EQ(fingerprint.size(), 16u);
  EXPECT_EQ(fingerprint.find_first_not_of("0123456789abcdef"), std::string::npos) << fingerprint;
  EXPECT_EQ(fingerprint_of(kRig), fingerprint);
}

TEST(RigFingerprint, IgnoresCommentsLayoutOrderAndDescription) {
  const std::string base = fingerprint_of(kRig);
  // Block style, comments, another key and LED order, another description: the same rig.
  const std::string rewritten = R"(# the same dome, written differently
leds:
  - {position_mm: [0, 0, 300.0], line: 2, id: 2}
  - id: 1
    line: 1            # second LED
    position_mm: [0, 300, 10]
  - {id: 0, line: 0, position_mm: [3e2, 0, 10]}
led_defaults: {limits: {max_duty: 0.50, max_on_us: 1000}}
trigger: {line: 10}
camera: {height: 48, width: 64}
dome_radius_mm: 300
name: tiny
description: another text
)";
  EXPECT_EQ(fingerprint_of(rewritten), base);
  EXPECT_EQ(fingerprint_of(replaced(kRig, "description: three LEDs\n", "")), base);
}

TEST(RigFingerprint, ChangesWithAnyFieldThatDescribesTheDome) {
  const std::string base = fingerprint_of(kRig);
  for (const auto& [from, to] : std::initializer_list<std::pair<std::string, std::string>>{
           {"max_on_us: 1000", "max_on_us: 999"},
           {"max_duty: 0.5", "max_duty: 0.4"},
           {"dome_radius_mm: 300", "dome_radius_mm: 301"},
           {"{id: 1, line: 1,", "{id: 1, line: 4,"},
           {"{id: 1, line: 1,", "{id: 1, line: {line: 1, active_low: true},"},
           {"[0, 300, 10]", "[0, 300, 11]"},
           {"trigger: {line: 10}", "trigger: {line: 10, pulse_us: 50}"},
           {"width: 64", "width: 65"},
           {"{id: 2, line: 2,", "{id: 3, line: 2,"},
       }) {
    EXPECT_NE(fingerprint_of(replaced(kRig, from, to)), base) << from << " -> " << to;
  }
}

TEST(RigFingerprint, TheShippedRigsDiffer) {
  const auto dir = testing::source_dir() / "hw/rigs";
  EXPECT_NE(rig_fingerprint(load_rig(dir / "sim-dome.yaml")),
            rig_fingerprint(load_rig(dir / "matrix-64.yaml")));
}

}  // namespace
}  // namespace lightstage
