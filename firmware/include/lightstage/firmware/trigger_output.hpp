#pragma once
// The camera trigger line: an output whose active level and pulse width come
// from the rig (trigger: {line, active_low, pulse_us}).

#include "lightstage/common/gpio.hpp"
#include "lightstage/common/rig.hpp"

#include <cstdint>
#include <memory>

namespace lightstage::firmware {

class TriggerOutput {
 public:
  // Requests the line inactive. Throws gpio::GpioError naming the line.
  TriggerOutput(const Rig& rig, gpio::Chip& chip, const gpio::ChipInfo& info);

  void assert_at(std::int64_t t_ns) { set(1, t_ns); }
  void release_at(std::int64_t t_ns) { set(0, t_ns); }
  bool asserted() const { return value_ != 0; }
  std::int64_t pulse_ns() const { return pulse_ns_; }

 private:
  void set(int value, std::int64_t t_ns);

  std::unique_ptr<gpio::OutputLines> line_;
  std::int64_t pulse_ns_;
  int value_ = 0;
};

// The strobe / exposure-active input as edge events, or nullptr when the rig
// has none (then only open-loop sequences run). Throws gpio::GpioError.
std::unique_ptr<gpio::EdgeInput> open_strobe_input(const Rig& rig, gpio::Chip& chip,
                                                   const gpio::ChipInfo& info);

}  // namespace lightstage::firmware
