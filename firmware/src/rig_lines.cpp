#include "lightstage/firmware/rig_lines.hpp"

#include <fmt/format.h>

#include <variant>

namespace lightstage::firmware {

std::vector<RigLine> rig_lines(const Rig& rig) {
  std::vector<RigLine> lines;
  lines.push_back({rig.trigger.line, "the camera trigger", false});
  if (rig.strobe) lines.push_back({rig.strobe->line, "the strobe input", false});
  for (const ShiftRegisterChain& chain : rig.chains) {
    const std::string prefix = "chain '" + chain.name + "' ";
    lines.push_back({chain.data, prefix + "data", true});
    lines.push_back({chain.clock, prefix + "clock", true});
    lines.push_back({chain.latch, prefix + "latch", true});
    if (chain.output_enable) lines.push_back({*chain.output_enable, prefix + "output enable", true});
  }
  for (const Led& led : rig.leds) {
    if (const auto* direct = std::get_if<DirectWiring>(&led.wiring)) {
      lines.push_back({direct->line, fmt::format("LED {}", led.id), true});
    }
  }
  return lines;
}

namespace {

std::optional<unsigned> find_offset(const gpio::ChipInfo& chip, const LineRef& line) {
  if (line.by_name()) {
    for (std::size_t i = 0; i < chip.line_names.size(); ++i) {
      if (chip.line_names[i] == line.name) return static_cast<unsigned>(i);
    }
    return std::nullopt;
  }
  if (line.offset < 0 || static_cast<std::size_t>(line.offset) >= chip.line_names.size()) return std::nullopt;
  return static_cast<unsigned>(line.offset);
}

std::string missing(const Rig& rig, const gpio::ChipInfo& chip, const LineRef& line, const std::string& use) {
  return line.by_name()
             ? fmt::format("{}: {} ({}) is not on chip \"{}\", which has no line of that name",
                           rig.source.string(), line.describe(), use, chip.label)
             : fmt::format("{}: {} ({}) is not on chip \"{}\", which has {} lines", rig.source.string(),
                           line.describe(), use, chip.label, chip.line_names.size());
}

}  // namespace

unsigned resolve_line(const Rig& rig, const gpio::ChipInfo& chip, const LineRef& line,
                      const std::string& use) {
  const auto offset = find_offset(chip, line);
  if (!offset) throw gpio::GpioError(missing(rig, chip, line, use));
  return *offset;
}

std::vector<LineCheck> check_rig_lines(const Rig& rig, const gpio::ChipInfo& chip) {
  std::vector<LineCheck> checks;
  for (const RigLine& line : rig_lines(rig)) {
    LineCheck check{line, find_offset(chip, line.line), {}};
    if (!check.offset) {
      check.problem =
          line.line.by_name() ? "no line of that name on the chip" : "offset beyond the chip's lines";
    } else if (*check.offset < chip.consumers.size() && !chip.consumers[*check.offset].empty()) {
      check.problem = fmt::format("busy, used by \"{}\"", chip.consumers[*check.offset]);
    }
    checks.push_back(std::move(check));
  }
  return checks;
}

}  // namespace lightstage::firmware
