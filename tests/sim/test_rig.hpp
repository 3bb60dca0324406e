#pragma once
// A tiny in-code rig for the sim tests: LEDs at the given positions, an
// orthographic camera of the given size.

#include "lightstage/common/rig.hpp"

#include <fmt/format.h>

#include <string>
#include <vector>

namespace lightstage::sim::testing {

inline Rig make_rig(const std::vector<Vec3>& leds, int width = 64, int height = 64, double pitch_mm = 1.6) {
  std::string yaml = fmt::format(
      "name: test\ndome_radius_mm: 300\ncamera: {{width: {}, height: {}, pixel_pitch_mm: {}}}\n"
      "trigger: {{line: 100}}\nled_defaults:\n  limits: {{max_on_us: 1000, max_duty: 0.5}}\nleds:\n",
      width, height, pitch_mm);
  for (std::size_t i = 0; i < leds.size(); ++i) {
    yaml += fmt::format("  - {{id: {}, line: {}, position_mm: [{}, {}, {}]}}\n", i + 1, i, leds[i].x(),
                        leds[i].y(), leds[i].z());
  }
  return parse_rig(yaml, "test-rig.yaml");
}

}  // namespace lightstage::sim::testing
