#pragma once
// A chain of 74HC595 shift registers seen from its pins: a rising edge on the
// shift clock shifts the data line in at bit 0 (so after `length` clocks the
// first bit shifted sits at the far end and the last one at bit 0, the first
// register's Q0); a rising edge on the latch (storage clock) copies the shift
// register to the outputs; the outputs drive only while output enable is
// active (always, on a chain without an OE line).
//
// Pin changes that happen in one step (one OutputLines::set) are sampled as
// the hardware would: edges see the other pins' values from before the step,
// so a latch and a clock rising together latch the bits from before the shift.

#include <vector>

namespace lightstage::sim::gpio {

struct ShiftRegisterPins {
  bool data = false;
  bool clock = false;
  bool latch = false;
  bool output_enable = true;  // active (outputs driving)
};

class ShiftRegisterChainModel {
 public:
  ShiftRegisterChainModel(int length, bool has_output_enable);

  // Applies one step of pin changes; returns true when the visible outputs changed.
  bool step(const ShiftRegisterPins& next);

  // Bit `bit` is driven high now (stored, and output enable active).
  bool output(int bit) const;
  const std::vector<bool>& shift_register() const { return shift_; }
  const std::vector<bool>& storage() const { return storage_; }
  const ShiftRegisterPins& pins() const { return pins_; }

 private:
  std::vector<bool> visible_outputs() const;

  std::vector<bool> shift_;
  std::vector<bool> storage_;
  ShiftRegisterPins pins_;
};

}  // namespace lightstage::sim::gpio
