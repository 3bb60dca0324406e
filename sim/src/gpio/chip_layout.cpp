#include "lightstage/sim/gpio/chip_layout.hpp"

#include "lightstage/common/error.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <map>
#include <set>

namespace lightstage::sim::gpio {
namespace {

// A rig line waiting for an offset: what it is, and what to call it if the
// rig does not name it.
struct PendingLine {
  LineRef ref;
  LineSpec spec;
  std::string default_name;
};

std::vector<PendingLine> rig_lines(const Rig& rig) {
  std::vector<PendingLine> lines;
  auto add = [&](const LineRef& ref, LineRole role, std::string default_name, int led_id = -1,
                 int chain = -1) {
    LineSpec spec;
    spec.role = role;
    spec.active_low = ref.active_low;
    spec.led_id = led_id;
    spec.chain = chain;
    lines.push_back({ref, spec, std::move(default_name)});
  };
  add(rig.trigger.line, LineRole::kTrigger, "TRIGGER");
  if (rig.trigger.focus) add(rig.trigger.focus->line, LineRole::kFocus, "FOCUS");
  if (rig.strobe) add(rig.strobe->line, LineRole::kStrobe, "STROBE");
  const bool prefix_chains = rig.chains.size() > 1;
  for (std::size_t i = 0; i < rig.chains.size(); ++i) {
    const auto& chain = rig.chains[i];
    const std::string prefix = prefix_chains ? chain.name + "_" : "";
    const int index = static_cast<int>(i);
    add(chain.data, LineRole::kChainData, prefix + "SR_DATA", -1, index);
    add(chain.clock, LineRole::kChainClock, prefix + "SR_CLK", -1, index);
    add(chain.latch, LineRole::kChainLatch, prefix + "SR_LATCH", -1, index);
    if (chain.output_enable)
      add(*chain.output_enable, LineRole::kChainOutputEnable, prefix + "SR_OE", -1, index);
  }
  for (const auto& led : rig.leds) {
    if (const auto* direct = std::get_if<DirectWiring>(&led.wiring)) {
      add(direct->line, LineRole::kLed, fmt::format("LED{}", led.id), led.id);
    }
  }
  return lines;
}

}  // namespace

std::string ChipLayout::display_name(unsigned offset) const {
  if (offset < lines.size() && !lines[offset].name.empty()) return lines[offset].name;
  return fmt::format("line{}", offset);
}

std::optional<unsigned> ChipLayout::resolve(const std::string& name_or_offset) const {
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (!lines[i].name.empty() && lines[i].name == name_or_offset) return static_cast<unsigned>(i);
  }
  unsigned offset = 0;
  const char* end = name_or_offset.data() + name_or_offset.size();
  const auto [ptr, ec] = std::from_chars(name_or_offset.data(), end, offset);
  if (!name_or_offset.empty() && ec == std::errc() && ptr == end && offset < lines.size()) return offset;
  return std::nullopt;
}

ChipLayout layout_from_rig(const Rig& rig) {
  ChipLayout layout;
  std::vector<PendingLine> pending = rig_lines(rig);

  // Lines with a rig offset first, so named-only lines fill the gaps around them.
  std::map<unsigned, std::size_t> by_offset;  // offset -> index into pending
  for (std::size_t i = 0; i < pending.size(); ++i) {
    if (!pending[i].ref.by_name()) by_offset[static_cast<unsigned>(pending[i].ref.offset)] = i;
  }
  unsigned next_free = 0;
  for (std::size_t i = 0; i < pending.size(); ++i) {
    if (!pending[i].ref.by_name()) continue;
    while (by_offset.contains(next_free)) ++next_free;
    by_offset[next_free] = i;
  }
  const unsigned line_count = by_offset.empty() ? 0 : by_offset.rbegin()->first + 1;
  layout.lines.resize(line_count);

  std::set<std::string> names;
  std::vector<unsigned> offset_of(pending.size());
  for (const auto& [offset, index] : by_offset) {
    PendingLine& line = pending[index];
    line.spec.name = line.ref.by_name() ? line.ref.name : line.default_name;
    if (!names.insert(line.spec.name).second) {
      fail("{}: two lines of the virtual chip would be called \"{}\"; name the line another way in the rig",
           rig.source.string(), line.spec.name);
    }
    layout.lines[offset] = line.spec;
    offset_of[index] = offset;
    if (line.spec.role == LineRole::kTrigger) layout.trigger = offset;
    if (line.spec.role == LineRole::kStrobe) layout.strobe = offset;
  }

  for (const auto& chain : rig.chains) {
    ChainSpec spec;
    spec.name = chain.name;
    spec.length = chain.length;
    spec.led_by_bit.assign(static_cast<std::size_t>(chain.length), -1);
    layout.chains.push_back(spec);
  }
  for (std::size_t i = 0; i < pending.size(); ++i) {
    const LineSpec& spec = pending[i].spec;
    if (spec.chain < 0) continue;
    ChainSpec& chain = layout.chains[static_cast<std::size_t>(spec.chain)];
    switch (spec.role) {
      case LineRole::kChainData:
        chain.data = offset_of[i];
        break;
      case LineRole::kChainClock:
        chain.clock = offset_of[i];
        break;
      case LineRole::kChainLatch:
        chain.latch = offset_of[i];
        break;
      case LineRole::kChainOutputEnable:
        chain.output_enable = offset_of[i];
        break;
      default:
        break;
    }
  }
  for (const auto& led : rig.leds) {
    const auto* wired = std::get_if<ChainWiring>(&led.wiring);
    if (!wired) continue;
    const auto chain = std::find_if(rig.chains.begin(), rig.chains.end(),
                                    [&](const ShiftRegisterChain& c) { return c.name == wired->chain; });
    if (chain == rig.chains.end() || wired->bit < 0 || wired->bit >= chain->length) {
      fail("{}: LED {} is wired to bit {} of chain '{}', which the rig does not have", rig.source.string(),
           led.id, wired->bit, wired->chain);
    }
    auto& bits = layout.chains[static_cast<std::size_t>(chain - rig.chains.begin())].led_by_bit;
    bits[static_cast<std::size_t>(wired->bit)] = led.id;
  }
  return layout;
}

}  // namespace lightstage::sim::gpio
