#include "lightstage/host/controller/sequences.hpp"

namespace lightstage {

proto::Sequence one_led_per_step(const std::vector<std::uint32_t>& led_ids,
                                 const OneLedPerStepOptions& options, std::uint32_t sequence_id) {
  proto::Sequence sequence;
  sequence.set_id(sequence_id);
  for (std::size_t i = 0; i < led_ids.size(); ++i) {
    proto::Step* step = sequence.add_steps();
    auto* led = step->add_leds();
    led->set_led_id(led_ids[i]);
    led->set_level(1.0f);
    step->set_settle_us(options.settle_us);
    step->set_trigger(options.trigger);
    step->set_exposure_us(options.exposure_us);
    step->set_wait_strobe(options.closed_loop);
    step->set_strobe_timeout_us(options.strobe_timeout_us);
    step->set_gap_us(options.gap_us);
    step->set_tag(static_cast<std::uint32_t>(i));
  }
  return sequence;
}

std::vector<std::uint32_t> led_ids(const proto::Info& info) {
  std::vector<std::uint32_t> ids;
  for (const auto& led : info.leds()) ids.push_back(led.id());
  return ids;
}

}  // namespace lightstage
