#include "lightstage/firmware/composite_led_driver.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace lightstage::firmware {

CompositeLedDriver::CompositeLedDriver(std::vector<std::unique_ptr<LedDriver>> drivers)
    : drivers_(std::move(drivers)) {}

void CompositeLedDriver::stage(std::span<const int> led_ids) {
  for (const int id : led_ids) {
    if (!carries(id)) throw gpio::GpioError(fmt::format("LED {} is on none of the rig's drivers", id));
  }
  for (auto& driver : drivers_) {
    std::vector<int> mine;
    for (const int id : led_ids) {
      if (driver->carries(id)) mine.push_back(id);
    }
    driver->stage(mine);
  }
}

std::int64_t CompositeLedDriver::commit(std::int64_t t_ns) {
  std::int64_t changed_ns = t_ns;
  for (auto& driver : drivers_) changed_ns = std::max(changed_ns, driver->commit(t_ns));
  return changed_ns;
}

bool CompositeLedDriver::carries(int led_id) const {
  return std::any_of(drivers_.begin(), drivers_.end(), [&](const auto& d) { return d->carries(led_id); });
}

std::string CompositeLedDriver::describe() const {
  std::string text;
  for (const auto& driver : drivers_) text += (text.empty() ? "" : " + ") + driver->describe();
  return text;
}

}  // namespace lightstage::firmware
