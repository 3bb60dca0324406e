#include "lightstage/firmware/trigger_output.hpp"

#include "lightstage/firmware/rig_lines.hpp"

#include <cmath>

namespace lightstage::firmware {

TriggerOutput::TriggerOutput(const Rig& rig, gpio::Chip& chip, const gpio::ChipInfo& info)
    : pulse_ns_(std::llround(rig.trigger.pulse_us * 1000.0)) {
  const auto request = [&](const LineRef& ref, const char* what) {
    const unsigned offset = resolve_line(rig, info, ref, what);
    const bool active_low[1] = {ref.active_low};
    const int initial[1] = {0};
    return chip.request_outputs(std::span<const unsigned>(&offset, 1), active_low, initial, kConsumer);
  };
  line_ = request(rig.trigger.line, "the camera trigger");
  if (rig.trigger.focus) {
    focus_ = request(rig.trigger.focus->line, "the camera's focus (half-press)");
    focus_lead_ns_ = std::llround(rig.trigger.focus->lead_us * 1000.0);
  }
}

void TriggerOutput::set(gpio::OutputLines& line, int& value, int level, std::int64_t t_ns) {
  const int values[1] = {level};
  line.set(values, t_ns);
  value = level;
}

void TriggerOutput::focus_at(std::int64_t t_ns) {
  if (focus_) set(*focus_, focus_value_, 1, t_ns);
}

void TriggerOutput::release_at(std::int64_t t_ns) {
  // The shutter first: a camera must never see a half-press end while its shutter is still closed.
  // The half-press is released even when the shutter line failed, then the failure goes on.
  try {
    set(*line_, value_, 0, t_ns);
  } catch (...) {
    if (focus_ && focus_value_ != 0) set(*focus_, focus_value_, 0, t_ns);
    throw;
  }
  if (focus_ && focus_value_ != 0) set(*focus_, focus_value_, 0, t_ns);
}

std::unique_ptr<gpio::EdgeInput> open_strobe_input(const Rig& rig, gpio::Chip& chip,
                                                   const gpio::ChipInfo& info) {
  if (!rig.strobe) return nullptr;
  const unsigned offset = resolve_line(rig, info, rig.strobe->line, "the strobe input");
  return chip.request_edges(offset, rig.strobe->line.active_low, kConsumer);
}

}  // namespace lightstage::firmware
