#include "lightstage/sim/gpio/shift_register.hpp"

namespace lightstage::sim::gpio {

ShiftRegisterChainModel::ShiftRegisterChainModel(int length, bool has_output_enable)
    : shift_(static_cast<std::size_t>(length), false), storage_(static_cast<std::size_t>(length), false) {
  // Without an OE line the outputs always drive; with one, they start disabled
  // until the firmware enables them (a pull-up keeps a real 74HC595's OE high).
  pins_.output_enable = !has_output_enable;
}

bool ShiftRegisterChainModel::step(const ShiftRegisterPins& next) {
  const std::vector<bool> before = visible_outputs();
  const bool latch_rises = next.latch && !pins_.latch;
  const bool clock_rises = next.clock && !pins_.clock;
  // Both edges sample the state before this step (see the header).
  if (latch_rises) storage_ = shift_;
  if (clock_rises && !shift_.empty()) {
    for (std::size_t i = shift_.size() - 1; i > 0; --i) shift_[i] = shift_[i - 1];
    shift_[0] = pins_.data;
  }
  pins_ = next;
  return visible_outputs() != before;
}

bool ShiftRegisterChainModel::output(int bit) const {
  return pins_.output_enable && storage_.at(static_cast<std::size_t>(bit));
}

std::vector<bool> ShiftRegisterChainModel::visible_outputs() const {
  if (!pins_.output_enable) return std::vector<bool>(storage_.size(), false);
  return storage_;
}

}  // namespace lightstage::sim::gpio
