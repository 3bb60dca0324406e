#include "lightstage/firmware/trigger_output.hpp"

#include "lightstage/firmware/rig_lines.hpp"

#include <cmath>

namespace lightstage::firmware {

TriggerOutput::TriggerOutput(const Rig& rig, gpio::Chip& chip, const gpio::ChipInfo& info)
    : pulse_ns_(std::llround(rig.trigger.pulse_us * 1000.0)) {
  const unsigned offset = resolve_line(rig, info, rig.trigger.line, "the camera trigger");
  const bool active_low[1] = {rig.trigger.line.active_low};
  const int initial[1] = {0};
  line_ = chip.request_outputs(std::span<const unsigned>(&offset, 1), active_low, initial, kConsumer);
}

void TriggerOutput::set(int value, std::int64_t t_ns) {
  const int values[1] = {value};
  line_->set(values, t_ns);
  value_ = value;
}

std::unique_ptr<gpio::EdgeInput> open_strobe_input(const Rig& rig, gpio::Chip& chip,
                                                   const gpio::ChipInfo& info) {
  if (!rig.strobe) return nullptr;
  const unsigned offset = resolve_line(rig, info, rig.strobe->line, "the strobe input");
  return chip.request_edges(offset, rig.strobe->line.active_low, kConsumer);
}

}  // namespace lightstage::firmware
