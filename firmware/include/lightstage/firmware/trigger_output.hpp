#pragma once
// The camera trigger line: an output whose active level and pulse width come
// from the rig (trigger: {line, active_low, pulse_us}), and a stills camera's
// half-press line when the rig has one (trigger.focus).

#include "lightstage/common/gpio.hpp"
#include "lightstage/common/rig.hpp"

#include <cstdint>
#include <memory>

namespace lightstage::firmware {

class TriggerOutput {
 public:
  // Requests the line(s) inactive. Throws gpio::GpioError naming the line.
  TriggerOutput(const Rig& rig, gpio::Chip& chip, const gpio::ChipInfo& info);

  void assert_at(std::int64_t t_ns) { set(*line_, value_, 1, t_ns); }
  // Releases the trigger and the half-press with it.
  void release_at(std::int64_t t_ns);
  bool asserted() const { return value_ != 0 || focus_value_ != 0; }
  std::int64_t pulse_ns() const { return pulse_ns_; }

  bool has_focus() const { return focus_ != nullptr; }
  std::int64_t focus_lead_ns() const { return focus_lead_ns_; }
  void focus_at(std::int64_t t_ns);  // no-op without a focus line

 private:
  static void set(gpio::OutputLines& line, int& value, int level, std::int64_t t_ns);

  std::unique_ptr<gpio::OutputLines> line_;
  std::unique_ptr<gpio::OutputLines> focus_;
  std::int64_t pulse_ns_;
  std::int64_t focus_lead_ns_ = 0;
  int value_ = 0;
  int focus_value_ = 0;
};

// The strobe / exposure-active input as edge events, or nullptr when the rig
// has none (then only open-loop sequences run). Throws gpio::GpioError.
std::unique_ptr<gpio::EdgeInput> open_strobe_input(const Rig& rig, gpio::Chip& chip,
                                                   const gpio::ChipInfo& info);

}  // namespace lightstage::firmware
