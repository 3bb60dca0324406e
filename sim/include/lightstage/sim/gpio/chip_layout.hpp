#pragma once
// The virtual gpiochip's lines, derived from a rig: which offset carries which
// name and what the line does in the dome (an LED, the camera trigger, the
// strobe input, a shift-register chain's data/clock/latch/output-enable).
//
// Naming: a line the rig names keeps that name; otherwise a direct LED line is
// "LED<id>", the trigger "TRIGGER", a stills camera's half-press "FOCUS", the strobe "STROBE", and a chain
// line "SR_DATA" / "SR_CLK" / "SR_LATCH" / "SR_OE" (prefixed with "<chain>_" when the rig has more than one
// chain). Offsets: the rig's where it gives one; lines referenced only by name take the lowest free offsets,
// in rig-file order (trigger, focus, strobe, chains, LEDs). Offsets no rig line uses stay unnamed.

#include "lightstage/common/rig.hpp"

#include <optional>
#include <string>
#include <vector>

namespace lightstage::sim::gpio {

enum class LineRole {
  kUnused,
  kLed,
  kTrigger,
  kFocus,
  kStrobe,
  kChainData,
  kChainClock,
  kChainLatch,
  kChainOutputEnable
};

struct LineSpec {
  std::string name;  // "" for an unused offset
  LineRole role = LineRole::kUnused;
  bool active_low = false;  // as wired in the rig: the line is active when its level is low
  int led_id = -1;          // kLed
  int chain = -1;           // chain roles: index into ChipLayout::chains
};

// One 74HC595-style chain: the offsets of its lines and which LED hangs on each bit.
struct ChainSpec {
  std::string name;
  unsigned data = 0;
  unsigned clock = 0;
  unsigned latch = 0;
  std::optional<unsigned> output_enable;
  int length = 0;
  std::vector<int> led_by_bit;  // LED id per bit, -1 where no LED is wired
};

struct ChipLayout {
  std::string label = "lightstage-sim";
  std::vector<LineSpec> lines;  // by offset
  std::vector<ChainSpec> chains;
  std::optional<unsigned> trigger;
  std::optional<unsigned> strobe;

  // "LED17", or "line96" for an unnamed offset.
  std::string display_name(unsigned offset) const;
  // The offset of a line given by name or by decimal offset; nullopt if none.
  std::optional<unsigned> resolve(const std::string& name_or_offset) const;
};

// Throws InputError naming the rig file when two lines would share a name.
ChipLayout layout_from_rig(const Rig& rig);

}  // namespace lightstage::sim::gpio
