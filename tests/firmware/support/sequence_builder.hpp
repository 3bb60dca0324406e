#pragma once
// Builds controller.proto sequences for tests, one step per call.

#include "lightstage/proto/controller.pb.h"

#include <cstdint>
#include <vector>

namespace lightstage::firmware::testing {

struct StepSpec {
  std::vector<int> leds;
  std::uint32_t settle_us = 200;
  bool trigger = true;
  std::uint32_t exposure_us = 1000;
  bool wait_strobe = false;
  std::uint32_t strobe_timeout_us = 0;
  std::uint32_t gap_us = 1000;
};

inline proto::Sequence make_sequence(std::uint32_t id, const std::vector<StepSpec>& steps) {
  proto::Sequence sequence;
  sequence.set_id(id);
  std::uint32_t tag = 0;
  for (const StepSpec& spec : steps) {
    proto::Step& step = *sequence.add_steps();
    for (const int led : spec.leds) {
      proto::LedLevel& level = *step.add_leds();
      level.set_led_id(static_cast<std::uint32_t>(led));
      level.set_level(1.0F);
    }
    step.set_settle_us(spec.settle_us);
    step.set_trigger(spec.trigger);
    step.set_exposure_us(spec.exposure_us);
    step.set_wait_strobe(spec.wait_strobe);
    step.set_strobe_timeout_us(spec.strobe_timeout_us);
    step.set_gap_us(spec.gap_us);
    step.set_tag(100 + tag++);
  }
  return sequence;
}

// One step per LED in `leds`, all alike otherwise.
inline proto::Sequence one_led_per_step(std::uint32_t id, const std::vector<int>& leds, StepSpec spec) {
  std::vector<StepSpec> steps;
  for (const int led : leds) {
    spec.leds = {led};
    steps.push_back(spec);
  }
  return make_sequence(id, steps);
}

}  // namespace lightstage::firmware::testing
