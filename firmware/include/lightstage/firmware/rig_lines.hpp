#pragma once
// The GPIO lines a rig uses, found on a chip. Rig files name lines by offset or
// by the name the board gives them; this turns each into an offset on the
// opened chip, with errors that name the rig file, the line and its use.

#include "lightstage/common/gpio.hpp"
#include "lightstage/common/rig.hpp"

#include <optional>
#include <string>
#include <vector>

namespace lightstage::firmware {

// The consumer label the daemon requests lines under (gpioinfo shows it).
inline constexpr const char* kConsumer = "lightstage-domed";

// One line the rig uses and what for ("LED 7", "the camera trigger", "chain 'leds' clock").
struct RigLine {
  LineRef line;
  std::string use;
  bool drives_leds = false;  // an LED line or a chain line: --dark drives these inactive
};

// Every line of the rig: trigger, strobe, chain lines, direct LED lines.
std::vector<RigLine> rig_lines(const Rig& rig);

// The offset of `line` on the chip. Throws gpio::GpioError naming the rig,
// the line, its use and the chip when the chip has no such line.
unsigned resolve_line(const Rig& rig, const gpio::ChipInfo& chip, const LineRef& line,
                      const std::string& use);

// --check: each rig line, where it is on the chip, and what is wrong with it.
struct LineCheck {
  RigLine line;
  std::optional<unsigned> offset;
  std::string problem;  // "" when the line exists and is free
};
std::vector<LineCheck> check_rig_lines(const Rig& rig, const gpio::ChipInfo& chip);

}  // namespace lightstage::firmware
