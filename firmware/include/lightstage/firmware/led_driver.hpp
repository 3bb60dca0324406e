#pragma once
// Switching the dome's LEDs. A driver lights exactly a given set of LEDs (every
// other LED dark) as one operation, stamped with the caller's time. The rig
// chooses the drivers: one GPIO line per LED (DirectLedDriver), a 74HC595
// shift-register chain (ShiftRegisterLedDriver), or a mix of both.

#include "lightstage/common/clock.hpp"
#include "lightstage/common/gpio.hpp"
#include "lightstage/common/rig.hpp"

#include <cstdint>
#include <memory>
#include <span>
#include <string>

namespace lightstage::firmware {

class LedDriver {
 public:
  virtual ~LedDriver() = default;
  // Prepares the next state without changing what the LEDs show: a chain
  // shifts it into its registers, so that commit() at a deadline is one
  // quick latch. `led_ids` are lit, every other LED dark; ids the driver does
  // not carry are refused (the composite hands each driver its own). Throws
  // gpio::GpioError.
  virtual void stage(std::span<const int> led_ids) = 0;
  // Shows the staged state, stamped `t_ns` (CLOCK_MONOTONIC). Returns when the
  // LEDs actually changed: `t_ns` for direct lines, the latch edge for a chain.
  virtual std::int64_t commit(std::int64_t t_ns) = 0;
  virtual bool carries(int led_id) const = 0;
  virtual std::string describe() const = 0;

  std::int64_t show(std::span<const int> led_ids, std::int64_t t_ns) {
    stage(led_ids);
    return commit(t_ns);
  }
  std::int64_t all_off(std::int64_t t_ns) { return show({}, t_ns); }
};

// The drivers for every LED of the rig on `chip`: all LEDs start dark. The
// clock paces shift-register clocking (clock_period_us) and stamps it.
// Throws gpio::GpioError naming the line when one is missing or busy.
std::unique_ptr<LedDriver> make_led_driver(const Rig& rig, gpio::Chip& chip, Clock& clock);

}  // namespace lightstage::firmware
