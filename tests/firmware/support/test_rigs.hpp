#pragma once
// Small rigs for the firmware tests, in the rig-file format (docs/rig-format.md).

#include "lightstage/common/rig.hpp"

#include <string>

namespace lightstage::firmware::testing {

// Four LEDs on lines 0..3 (LED 2 active-low), for the rigs below.
inline constexpr const char* kFourDirectLeds = R"(leds:
  - {id: 0, line: 0, position_mm: [0, 0, 300]}
  - {id: 1, line: 1, position_mm: [300, 0, 0]}
  - {id: 2, line: {line: 2, active_low: true}, position_mm: [0, 300, 0]}
  - {id: 3, line: 3, position_mm: [-300, 0, 0]}
)";

// The four LEDs, trigger on 8, strobe on 9.
// Limits by default: 10 ms on-time, duty 0.5 over 100 ms.
inline Rig direct_rig(double max_on_us = 10000, double max_duty = 0.5, double duty_window_us = 100000) {
  return parse_rig(R"(name: direct-4
dome_radius_mm: 300
camera: {width: 8, height: 8}
trigger: {line: 8, pulse_us: 100}
strobe: {line: 9, timeout_us: 20000}
led_defaults:
  limits: {max_on_us: )" +
                       std::to_string(max_on_us) + ", max_duty: " + std::to_string(max_duty) +
                       ", duty_window_us: " + std::to_string(duty_window_us) + "}\n" + kFourDirectLeds,
                   "direct-4.yaml");
}

// The four LEDs with a DSLR on its remote port: shutter on 8 (a 50 ms press),
// half-press on 10 held 20 ms before it, 30 ms shutter lag, no strobe.
inline Rig dslr_rig(double max_on_us = 200000) {
  return parse_rig(R"(name: dslr-4
dome_radius_mm: 300
camera: {width: 8, height: 8}
trigger:
  line: 8
  pulse_us: 50000
  focus: {line: 10, lead_us: 20000}
  shutter_lag_us: 30000
  arrival_timeout_us: 2000000
led_defaults:
  limits: {max_on_us: )" +
                       std::to_string(max_on_us) + ", max_duty: 0.9, duty_window_us: 10000000}\n" +
                       kFourDirectLeds,
                   "dslr-4.yaml");
}

// Sixteen LEDs (ids 100..115) on one chain of two 74HC595 (bit = id - 100),
// named lines SR_DATA / SR_CLK / SR_LATCH / SR_OE (active low), trigger CAM_TRIG.
inline Rig chain_rig() {
  std::string leds;
  for (int bit = 0; bit < 16; ++bit) {
    leds += "  - {id: " + std::to_string(100 + bit) + ", chain: leds, bit: " + std::to_string(bit) +
            ", position_mm: [" + std::to_string(10 + bit) + ", 0, 300]}\n";
  }
  return parse_rig(R"(name: chain-16
dome_radius_mm: 300
camera: {width: 8, height: 8}
trigger: {line: CAM_TRIG, pulse_us: 50}
chains:
  - {name: leds, data: SR_DATA, clock: SR_CLK, latch: SR_LATCH, output_enable: {line: SR_OE, active_low: true},
     length: 16, clock_period_us: 0.5}
led_defaults:
  limits: {max_on_us: 500000, max_duty: 0.25, duty_window_us: 4000000}
leds:
)" + leds,
                   "chain-16.yaml");
}

// Line names of the fake chip for chain_rig().
inline constexpr unsigned kSrData = 0, kSrClock = 1, kSrLatch = 2, kSrOutputEnable = 3, kCamTrig = 4;

}  // namespace lightstage::firmware::testing
