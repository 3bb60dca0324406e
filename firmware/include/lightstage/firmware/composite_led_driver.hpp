#pragma once
// A rig whose LEDs hang on several drivers (direct lines and/or several
// chains): each driver gets its own LEDs; commit() latches them all.

#include "lightstage/firmware/led_driver.hpp"

#include <vector>

namespace lightstage::firmware {

class CompositeLedDriver final : public LedDriver {
 public:
  explicit CompositeLedDriver(std::vector<std::unique_ptr<LedDriver>> drivers);

  void stage(std::span<const int> led_ids) override;
  std::int64_t commit(std::int64_t t_ns) override;
  bool carries(int led_id) const override;
  std::string describe() const override;

 private:
  std::vector<std::unique_ptr<LedDriver>> drivers_;
};

}  // namespace lightstage::firmware
