#pragma once
// Faults the simulated world can inject (lightstage-sim --fault KIND[:ARG], or
// at run time through sim_gpio.proto's InjectFault). See docs/sim-gpio.md.
//   lose-strobe:N      the N-th camera trigger (counting from 1 since the sim
//                      started) gets no strobe: the camera "missed" it
//   stuck:LINE         LINE (name or offset) ignores sets and keeps its value
//   drop-connection:N  the sim closes a firmware connection right after
//                      answering its N-th message (once)

#include <string>

namespace lightstage::sim::gpio {

struct Fault {
  enum class Kind { kLoseStrobe, kStuck, kDropConnection };
  Kind kind = Kind::kLoseStrobe;
  int count = 0;     // lose-strobe, drop-connection
  std::string line;  // stuck
  std::string text;  // as given, for messages
};

// Throws InputError naming the text and the accepted forms.
Fault parse_fault(const std::string& text);

}  // namespace lightstage::sim::gpio
