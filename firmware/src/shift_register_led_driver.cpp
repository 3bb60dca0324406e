#include "lightstage/firmware/shift_register_led_driver.hpp"

#include "lightstage/common/log.hpp"
#include "lightstage/firmware/rig_lines.hpp"

#include <fmt/format.h>

#include <cmath>
#include <variant>

namespace lightstage::firmware {

ShiftRegisterLedDriver::ShiftRegisterLedDriver(const Rig& rig, const ShiftRegisterChain& chain,
                                               gpio::Chip& chip, const gpio::ChipInfo& info, Clock& clock)
    : chain_name_(chain.name),
      length_(chain.length),
      half_period_ns_(std::max<std::int64_t>(1, std::llround(chain.clock_period_us * 500.0))),
      has_output_enable_(chain.output_enable.has_value()),
      clock_(clock) {
  for (const Led& led : rig.leds) {
    if (const auto* bit = std::get_if<ChainWiring>(&led.wiring); bit && bit->chain == chain.name) {
      bit_of_[led.id] = bit->bit;
    }
  }
  const std::string prefix = "chain '" + chain.name + "' ";
  std::vector<unsigned> offsets = {resolve_line(rig, info, chain.data, prefix + "data"),
                                   resolve_line(rig, info, chain.clock, prefix + "clock"),
                                   resolve_line(rig, info, chain.latch, prefix + "latch")};
  bool active_low[4] = {chain.data.active_low, chain.clock.active_low, chain.latch.active_low, false};
  if (has_output_enable_) {
    offsets.push_back(resolve_line(rig, info, *chain.output_enable, prefix + "output enable"));
    active_low[kOutputEnable] = chain.output_enable->active_low;
  }
  // Everything low and the outputs disabled until the chain holds zeros.
  values_.assign(offsets.size(), 0);
  lines_ =
      chip.request_outputs(offsets, std::span<const bool>(active_low, offsets.size()), values_, kConsumer);
  last_change_ns_ = clock_.now_ns();
  std::int64_t t = last_change_ns_;
  shift_and_latch(std::vector<int>(static_cast<std::size_t>(length_), 0), t);
  if (has_output_enable_) {
    values_[kOutputEnable] = 1;
    step(t);
  }
}

ShiftRegisterLedDriver::~ShiftRegisterLedDriver() {
  // Best effort: the daemon's dark path already cleared the chain; this also
  // covers a driver dropped on an error path.
  try {
    std::int64_t t = clock_.now_ns();
    shift_and_latch(std::vector<int>(static_cast<std::size_t>(length_), 0), t);
    if (has_output_enable_) {
      values_[kOutputEnable] = 0;
      step(t);
    }
  } catch (const std::exception& e) {
    logger("firmware")->error("chain '{}': clearing on shutdown failed: {}", chain_name_, e.what());
  }
}

void ShiftRegisterLedDriver::step(std::int64_t& t_ns) {
  t_ns = std::max(t_ns, last_change_ns_ + half_period_ns_);
  if (clock_.now_ns() < t_ns) clock_.sleep_until(t_ns);
  t_ns = std::max(t_ns, clock_.now_ns());
  lines_->set(values_, t_ns);
  last_change_ns_ = t_ns;
}

void ShiftRegisterLedDriver::shift(const std::vector<int>& bits, std::int64_t& t_ns) {
  // Highest bit first: after `length` clocks, bit 0 sits in the first register's Q0.
  for (int bit = length_ - 1; bit >= 0; --bit) {
    values_[kData] = bits[static_cast<std::size_t>(bit)];
    values_[kClock] = 0;
    step(t_ns);
    values_[kClock] = 1;
    step(t_ns);
  }
  values_[kClock] = 0;
  values_[kData] = 0;
  step(t_ns);
}

std::int64_t ShiftRegisterLedDriver::latch(std::int64_t t_ns) {
  values_[kLatch] = 1;
  step(t_ns);
  const std::int64_t latched_ns = t_ns;
  values_[kLatch] = 0;
  step(t_ns);
  return latched_ns;
}

std::int64_t ShiftRegisterLedDriver::shift_and_latch(const std::vector<int>& bits, std::int64_t t_ns) {
  shift(bits, t_ns);
  return latch(t_ns);
}

void ShiftRegisterLedDriver::stage(std::span<const int> led_ids) {
  std::vector<int> bits(static_cast<std::size_t>(length_), 0);
  for (const int id : led_ids) {
    const auto it = bit_of_.find(id);
    if (it == bit_of_.end()) {
      throw gpio::GpioError(fmt::format("LED {} is not on shift-register chain '{}'", id, chain_name_));
    }
    bits[static_cast<std::size_t>(it->second)] = 1;
  }
  std::int64_t t_ns = clock_.now_ns();
  shift(bits, t_ns);
}

std::int64_t ShiftRegisterLedDriver::commit(std::int64_t t_ns) { return latch(t_ns); }

std::string ShiftRegisterLedDriver::describe() const {
  return fmt::format("{} LEDs on shift-register chain '{}' ({} bits{})", bit_of_.size(), chain_name_, length_,
                     has_output_enable_ ? ", output enable" : "");
}

}  // namespace lightstage::firmware
