#pragma once
// One GPIO line per LED, all requested together as one output request (the
// gpiod backend splits it into bulks of at most 64 lines).

#include "lightstage/firmware/led_driver.hpp"

#include <map>
#include <vector>

namespace lightstage::firmware {

class DirectLedDriver final : public LedDriver {
 public:
  // The rig's directly wired LEDs; requests their lines dark.
  DirectLedDriver(const Rig& rig, gpio::Chip& chip, const gpio::ChipInfo& info);

  void stage(std::span<const int> led_ids) override;
  std::int64_t commit(std::int64_t t_ns) override;
  bool carries(int led_id) const override { return index_.contains(led_id); }
  std::string describe() const override;

 private:
  std::map<int, std::size_t> index_;  // LED id -> position in the request
  std::unique_ptr<gpio::OutputLines> lines_;
  std::vector<int> staged_;
};

}  // namespace lightstage::firmware
