#pragma once
// Holding LEDs lit by hand (`lightstage ctl leds`): the controller may switch
// them off itself sooner (an LED's on-time limit, its watchdog); that is a
// fault to report, not a hold that went as asked.

#include "lightstage/host/controller/controller_client.hpp"

#include <chrono>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace lightstage {

struct LedHold {
  std::int64_t held_ms = 0;
  bool faulted = false;
  std::string fault;  // the controller's last fault, when it faulted
};

// Lights `levels` (LED id, level) for `duration`, watching the controller's
// status, and darkens the dome at the end, faulted or not.
LedHold hold_leds(ControllerClient& client, const std::vector<std::pair<std::uint32_t, float>>& levels,
                  std::chrono::milliseconds duration);

}  // namespace lightstage
