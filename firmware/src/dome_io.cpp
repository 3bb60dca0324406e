#include "lightstage/firmware/dome_io.hpp"

namespace lightstage::firmware {

DomeIo open_dome_io(const Rig& rig, gpio::Chip& chip, Clock& clock) {
  DomeIo io;
  io.leds = make_led_driver(rig, chip, clock);  // requested dark
  const gpio::ChipInfo info = chip.info();
  io.trigger = std::make_unique<TriggerOutput>(rig, chip, info);
  io.strobe = open_strobe_input(rig, chip, info);
  return io;
}

std::string drive_leds_dark(const Rig& rig, gpio::Chip& chip, Clock& clock) {
  // The drivers request their lines inactive and clear the chains on
  // construction; show({}) and the destructor do it once more.
  const std::unique_ptr<LedDriver> leds = make_led_driver(rig, chip, clock);
  leds->all_off(clock.now_ns());
  return leds->describe() + ": all dark";
}

}  // namespace lightstage::firmware
