#pragma once
// Everything the controller drives on the GPIO chip: the LEDs (through the
// rig's drivers), the camera trigger, and the optional strobe input.

#include "lightstage/common/clock.hpp"
#include "lightstage/common/gpio.hpp"
#include "lightstage/common/rig.hpp"
#include "lightstage/firmware/led_driver.hpp"
#include "lightstage/firmware/trigger_output.hpp"

#include <memory>

namespace lightstage::firmware {

struct DomeIo {
  std::unique_ptr<LedDriver> leds;
  std::unique_ptr<TriggerOutput> trigger;
  std::unique_ptr<gpio::EdgeInput> strobe;  // null without a strobe line
};

// Requests every line of the rig on `chip`: LEDs dark, trigger inactive.
// Throws gpio::GpioError naming the line that is missing or busy.
DomeIo open_dome_io(const Rig& rig, gpio::Chip& chip, Clock& clock);

// --dark: requests the rig's LED lines (direct lines, chain lines) and drives
// every LED inactive (a chain is cleared, latched and its OE released), then
// releases them. Returns what it did, one line per driver.
std::string drive_leds_dark(const Rig& rig, gpio::Chip& chip, Clock& clock);

}  // namespace lightstage::firmware
