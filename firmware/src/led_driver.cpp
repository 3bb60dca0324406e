#include "lightstage/firmware/led_driver.hpp"

#include "lightstage/firmware/composite_led_driver.hpp"
#include "lightstage/firmware/direct_led_driver.hpp"
#include "lightstage/firmware/shift_register_led_driver.hpp"

#include <variant>

namespace lightstage::firmware {

std::unique_ptr<LedDriver> make_led_driver(const Rig& rig, gpio::Chip& chip, Clock& clock) {
  const gpio::ChipInfo info = chip.info();
  std::vector<std::unique_ptr<LedDriver>> drivers;
  const bool any_direct = std::any_of(rig.leds.begin(), rig.leds.end(), [](const Led& led) {
    return std::holds_alternative<DirectWiring>(led.wiring);
  });
  if (any_direct) drivers.push_back(std::make_unique<DirectLedDriver>(rig, chip, info));
  for (const ShiftRegisterChain& chain : rig.chains) {
    drivers.push_back(std::make_unique<ShiftRegisterLedDriver>(rig, chain, chip, info, clock));
  }
  if (drivers.size() == 1) return std::move(drivers.front());
  return std::make_unique<CompositeLedDriver>(std::move(drivers));
}

}  // namespace lightstage::firmware
