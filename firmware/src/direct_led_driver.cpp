#include "lightstage/firmware/direct_led_driver.hpp"

#include "lightstage/firmware/rig_lines.hpp"

#include <fmt/format.h>

#include <variant>

namespace lightstage::firmware {

DirectLedDriver::DirectLedDriver(const Rig& rig, gpio::Chip& chip, const gpio::ChipInfo& info) {
  std::vector<unsigned> offsets;
  std::vector<char> active_low;  // std::vector<bool> has no span
  for (const Led& led : rig.leds) {
    const auto* direct = std::get_if<DirectWiring>(&led.wiring);
    if (!direct) continue;
    index_[led.id] = offsets.size();
    offsets.push_back(resolve_line(rig, info, direct->line, fmt::format("LED {}", led.id)));
    active_low.push_back(direct->line.active_low);
  }
  staged_.assign(offsets.size(), 0);
  const std::unique_ptr<bool[]> low(new bool[active_low.size()]);
  for (std::size_t i = 0; i < active_low.size(); ++i) low[i] = active_low[i] != 0;
  lines_ =
      chip.request_outputs(offsets, std::span<const bool>(low.get(), active_low.size()), staged_, kConsumer);
}

void DirectLedDriver::stage(std::span<const int> led_ids) {
  std::vector<int> values(staged_.size(), 0);
  for (const int id : led_ids) {
    const auto it = index_.find(id);
    if (it == index_.end()) throw gpio::GpioError(fmt::format("LED {} is not wired to a direct line", id));
    values[it->second] = 1;
  }
  staged_ = std::move(values);
}

std::int64_t DirectLedDriver::commit(std::int64_t t_ns) {
  lines_->set(staged_, t_ns);  // one request: every LED line together
  return t_ns;
}

std::string DirectLedDriver::describe() const {
  return fmt::format("{} LEDs on direct lines", index_.size());
}

}  // namespace lightstage::firmware
