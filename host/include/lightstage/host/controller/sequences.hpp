#pragma once
// Sequences the host builds for the controller.

#include "lightstage/proto/controller.pb.h"

#include <cstdint>
#include <vector>

namespace lightstage {

struct OneLedPerStepOptions {
  std::uint32_t settle_us = 1'000;     // LED on -> trigger
  std::uint32_t exposure_us = 10'000;  // open loop: LEDs lit after the trigger
  std::uint32_t gap_us = 1'000;        // dark time between steps
  bool closed_loop = false;            // wait for the camera's strobe instead of exposure_us
  std::uint32_t strobe_timeout_us = 500'000;
  bool trigger = true;
};

// One step per LED, in the order given, each LED alone at full level: what a
// capture runs, and what `lightstage ctl run-test-sequence` runs on a new dome.
proto::Sequence one_led_per_step(const std::vector<std::uint32_t>& led_ids,
                                 const OneLedPerStepOptions& options, std::uint32_t sequence_id);

// The LED ids a controller reported in Info, in its order.
std::vector<std::uint32_t> led_ids(const proto::Info& info);

}  // namespace lightstage
