#pragma once
// Shared by the virtual-gpiochip tests: the shipped rigs, a bit-banged 74HC595
// writer over any "set these lines" function, and timeline filters.

#include "lightstage/common/rig.hpp"
#include "lightstage/sim/gpio/timeline.hpp"
#include "lightstage/testing/paths.hpp"

#include <algorithm>
#include <functional>
#include <string>
#include <vector>

namespace lightstage::sim::gpio::testing {

inline Rig shipped_rig(const std::string& name) {
  return load_rig(lightstage::testing::source_dir() / "hw" / "rigs" / (name + ".yaml"));
}

// Pins of a chain in request order: data, clock, latch, output enable.
using SetPins = std::function<void(const std::vector<int>& data_clock_latch_oe, std::int64_t t_ns)>;

// Shifts `bits` (bit 0 last, as the rig numbers them), latches, and enables
// the outputs, the way a firmware driver bit-bangs a 74HC595 chain: data set
// before the clock's rising edge, one step per change. Returns the next free time.
inline std::int64_t write_chain(const SetPins& set, const std::vector<bool>& bits, std::int64_t t_ns) {
  for (std::size_t i = bits.size(); i-- > 0;) {
    const int d = bits[i] ? 1 : 0;
    set({d, 0, 0, 1}, t_ns += 10);
    set({d, 1, 0, 1}, t_ns += 10);
    set({d, 0, 0, 1}, t_ns += 10);
  }
  set({0, 0, 1, 1}, t_ns += 10);
  set({0, 0, 0, 1}, t_ns += 10);
  return t_ns;
}

inline std::vector<TimelineEntry> entries_for(const std::vector<TimelineEntry>& timeline,
                                              const std::string& line) {
  std::vector<TimelineEntry> out;
  std::copy_if(timeline.begin(), timeline.end(), std::back_inserter(out),
               [&](const TimelineEntry& e) { return e.line == line; });
  return out;
}

inline std::vector<TimelineEntry> led_entries(const std::vector<TimelineEntry>& timeline) {
  std::vector<TimelineEntry> out;
  std::copy_if(timeline.begin(), timeline.end(), std::back_inserter(out),
               [](const TimelineEntry& e) { return e.led >= 0; });
  return out;
}

}  // namespace lightstage::sim::gpio::testing
