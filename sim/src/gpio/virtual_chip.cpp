#include "lightstage/sim/gpio/virtual_chip.hpp"

#include "lightstage/common/clock.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace lightstage::sim::gpio {

using lightstage::gpio::GpioError;

void VirtualChipOptions::check() const {
  if (strobe_delay_ns < 0) fail("strobe delay must not be negative, got {} ns", strobe_delay_ns);
  if (strobe_exposure_ns <= 0) fail("strobe exposure must be positive, got {} ns", strobe_exposure_ns);
}

VirtualChipOptions chip_options_for(const Rig& rig) {
  VirtualChipOptions options;
  options.strobe = rig.strobe.has_value();
  options.strobe_exposure_ns = std::llround(rig.camera.exposure_us * 1000.0);
  return options;
}

VirtualChip::VirtualChip(ChipLayout layout, VirtualChipOptions options)
    : layout_(std::move(layout)),
      options_(options),
      strobe_exposure_ns_(options.strobe_exposure_ns),
      lines_(layout_.lines.size()) {
  options_.check();
  // Every line starts inactive as wired (pull resistors keep the dome dark).
  for (std::size_t i = 0; i < lines_.size(); ++i) lines_[i].level = layout_.lines[i].active_low;
  for (const auto& chain : layout_.chains)
    chains_.emplace_back(chain.length, chain.output_enable.has_value());
  if (options_.strobe && !layout_.strobe) {
    logger("sim")->warn("the rig has no strobe line: strobe emulation is off");
  }
}

void VirtualChip::add_timeline_sink(std::shared_ptr<TimelineSink> sink) {
  const std::lock_guard lock(mutex_);
  sinks_.push_back(std::move(sink));
}

lightstage::gpio::ChipInfo VirtualChip::info() const {
  const std::lock_guard lock(mutex_);
  lightstage::gpio::ChipInfo info;
  info.label = layout_.label;
  for (std::size_t i = 0; i < lines_.size(); ++i) {
    info.line_names.push_back(layout_.lines[i].name);
    info.consumers.push_back(lines_[i].owner ? lines_[i].consumer : "");
  }
  return info;
}

ClientId VirtualChip::connect() {
  const std::lock_guard lock(mutex_);
  return next_client_++;
}

void VirtualChip::disconnect(ClientId client) {
  const std::lock_guard lock(mutex_);
  // The connection is gone (the firmware exited or died): its lines are freed
  // and, as on a rig wired with the pull resistors hw/docs/firmware.md asks
  // for, each output falls to its inactive level — LEDs dark, a chain's
  // output-enable off.
  std::vector<LevelChange> floating;
  for (unsigned offset = 0; offset < lines_.size(); ++offset) {
    LineState& line = lines_[offset];
    if (line.owner != client) continue;
    if (line.output && !line.stuck && active_of(offset))
      floating.push_back({offset, layout_.lines[offset].active_low});
    line.owner = 0;
    line.consumer.clear();
  }
  if (!floating.empty()) {
    const auto notices = apply(floating, monotonic_now_ns());
    (void)notices;  // nobody holds these lines any more
  }
}

std::string VirtualChip::describe_line(unsigned offset) const {
  if (offset < layout_.lines.size() && !layout_.lines[offset].name.empty()) {
    return fmt::format("line {} \"{}\"", offset, layout_.lines[offset].name);
  }
  return fmt::format("line {}", offset);
}

void VirtualChip::check_offset(unsigned offset) const {
  if (offset >= lines_.size()) {
    throw GpioError(
        fmt::format("{}: no line {} (the chip has {} lines)", layout_.label, offset, lines_.size()));
  }
}

bool VirtualChip::active_of(unsigned offset) const {
  return lines_[offset].level != layout_.lines[offset].active_low;
}

void VirtualChip::request_lines(ClientId client, std::span<const unsigned> offsets, bool output,
                                const std::string& consumer, std::span<const bool> active_low,
                                std::span<const int> initial, std::int64_t t_ns) {
  const std::lock_guard lock(mutex_);
  if (offsets.empty()) throw GpioError(layout_.label + ": a request needs at least one line");
  if (!active_low.empty() && active_low.size() != offsets.size()) {
    throw GpioError(fmt::format("{}: {} active_low flags for {} lines", layout_.label, active_low.size(),
                                offsets.size()));
  }
  if (!initial.empty() && initial.size() != offsets.size()) {
    throw GpioError(
        fmt::format("{}: {} initial values for {} lines", layout_.label, initial.size(), offsets.size()));
  }
  for (std::size_t i = 0; i < offsets.size(); ++i) {
    check_offset(offsets[i]);
    if (std::find(offsets.begin(), offsets.begin() + static_cast<std::ptrdiff_t>(i), offsets[i]) !=
        offsets.begin() + static_cast<std::ptrdiff_t>(i)) {
      throw GpioError(
          fmt::format("{}: {} is requested twice in one request", layout_.label, describe_line(offsets[i])));
    }
    const LineState& line = lines_[offsets[i]];
    if (line.owner != 0) {
      throw GpioError(fmt::format("{}: {} is busy: already requested by \"{}\"", layout_.label,
                                  describe_line(offsets[i]), line.consumer));
    }
  }
  std::vector<LevelChange> changes;
  for (std::size_t i = 0; i < offsets.size(); ++i) {
    LineState& line = lines_[offsets[i]];
    line.owner = client;
    line.consumer = consumer;
    line.output = output;
    line.request_active_low = !active_low.empty() && active_low[i];
    if (output && !line.stuck) {
      const bool logical = !initial.empty() && initial[i] != 0;
      const bool level = logical != line.request_active_low;
      if (level != line.level) changes.push_back({offsets[i], level});
    }
  }
  // Initial levels change outputs only: nobody watches them for edges.
  apply(changes, t_ns != 0 ? t_ns : monotonic_now_ns());
}

std::vector<EdgeNotice> VirtualChip::set_values(ClientId client, std::span<const unsigned> offsets,
                                                std::span<const int> values, std::int64_t t_ns) {
  const std::lock_guard lock(mutex_);
  if (values.size() != offsets.size()) {
    throw GpioError(fmt::format("{}: {} values for {} lines", layout_.label, values.size(), offsets.size()));
  }
  for (const unsigned offset : offsets) {
    check_offset(offset);
    const LineState& line = lines_[offset];
    if (line.owner != client || !line.output) {
      throw GpioError(fmt::format(
          "{}: {} is not requested as an output by this connection{}", layout_.label, describe_line(offset),
          line.owner ? fmt::format(" (held by \"{}\")", line.consumer) : std::string()));
    }
  }
  std::vector<LevelChange> changes;
  for (std::size_t i = 0; i < offsets.size(); ++i) {
    const LineState& line = lines_[offsets[i]];
    if (line.stuck) continue;  // fault: the line ignores sets
    const bool level = (values[i] != 0) != line.request_active_low;
    if (level != line.level) changes.push_back({offsets[i], level});
  }
  return apply(changes, t_ns);
}

void VirtualChip::release_lines(ClientId client, std::span<const unsigned> offsets) {
  const std::lock_guard lock(mutex_);
  for (const unsigned offset : offsets) {
    check_offset(offset);
    if (lines_[offset].owner != client) {
      throw GpioError(
          fmt::format("{}: {} is not held by this connection", layout_.label, describe_line(offset)));
    }
  }
  for (const unsigned offset : offsets) {
    lines_[offset].owner = 0;
    lines_[offset].consumer.clear();
  }
}

std::vector<EdgeNotice> VirtualChip::apply(const std::vector<LevelChange>& changes, std::int64_t t_ns) {
  std::vector<EdgeNotice> notices;
  if (changes.empty()) return notices;
  std::vector<TimelineEntry> entries;

  // Chains see the whole step at once (shift_register.hpp), so gather each
  // touched chain's next pins before applying anything.
  std::vector<std::optional<ShiftRegisterPins>> next_pins(chains_.size());
  for (const auto& change : changes) {
    const LineSpec& spec = layout_.lines[change.offset];
    if (spec.chain < 0) continue;
    auto& pins = next_pins[static_cast<std::size_t>(spec.chain)];
    if (!pins) pins = chains_[static_cast<std::size_t>(spec.chain)].pins();
    const bool active = change.level != spec.active_low;
    switch (spec.role) {
      case LineRole::kChainData:
        pins->data = active;
        break;
      case LineRole::kChainClock:
        pins->clock = active;
        break;
      case LineRole::kChainLatch:
        pins->latch = active;
        break;
      case LineRole::kChainOutputEnable:
        pins->output_enable = active;
        break;
      default:
        break;
    }
  }

  bool trigger_fired = false;
  for (const auto& change : changes) {
    LineState& line = lines_[change.offset];
    line.level = change.level;
    const LineSpec& spec = layout_.lines[change.offset];
    const bool active = active_of(change.offset);
    TimelineEntry entry;
    entry.t_ns = t_ns;
    entry.line = layout_.display_name(change.offset);
    entry.value = active ? 1 : 0;
    if (spec.role == LineRole::kLed) entry.led = spec.led_id;
    entries.push_back(std::move(entry));
    if (spec.role == LineRole::kTrigger && active) trigger_fired = true;
    if (line.owner != 0 && !line.output) {
      notices.push_back({line.owner, {change.offset, change.level != line.request_active_low, t_ns}});
    }
  }

  for (std::size_t c = 0; c < chains_.size(); ++c) {
    if (!next_pins[c]) continue;
    const ChainSpec& spec = layout_.chains[c];
    std::vector<bool> before(spec.led_by_bit.size());
    for (std::size_t bit = 0; bit < before.size(); ++bit)
      before[bit] = chains_[c].output(static_cast<int>(bit));
    if (!chains_[c].step(*next_pins[c])) continue;
    for (std::size_t bit = 0; bit < before.size(); ++bit) {
      const bool lit = chains_[c].output(static_cast<int>(bit));
      const int led = spec.led_by_bit[bit];
      if (lit == before[bit] || led < 0) continue;
      entries.push_back({t_ns, fmt::format("LED{}", led), lit ? 1 : 0, led, spec.name});
    }
  }

  if (trigger_fired) on_trigger(t_ns);
  publish(entries);
  return notices;
}

void VirtualChip::set_strobe_exposure_ns(std::int64_t exposure_ns) {
  if (exposure_ns <= 0) fail("strobe exposure must be positive, got {} ns", exposure_ns);
  const std::lock_guard lock(mutex_);
  strobe_exposure_ns_ = exposure_ns;
}

void VirtualChip::on_trigger(std::int64_t t_ns) {
  const int number = ++stats_.triggers;
  if (!options_.strobe || !layout_.strobe) return;
  if (lose_strobe_at_.contains(number)) {
    ++stats_.strobes_lost;
    logger("sim")->warn("fault lose-strobe:{}: trigger {} at {} ns gets no strobe", number, number, t_ns);
    return;
  }
  if (t_ns < camera_busy_until_ns_) {
    ++stats_.triggers_ignored;
    logger("sim")->warn(
        "trigger {} at {} ns came during an exposure (busy until {} ns): the camera ignores it", number, t_ns,
        camera_busy_until_ns_);
    return;
  }
  ++stats_.strobes;
  const std::int64_t start = t_ns + options_.strobe_delay_ns;
  const std::int64_t end = start + strobe_exposure_ns_;
  scheduled_.insert({start, true});
  scheduled_.insert({end, false});
  camera_busy_until_ns_ = end;
}

std::optional<std::int64_t> VirtualChip::next_due_ns() const {
  const std::lock_guard lock(mutex_);
  if (scheduled_.empty()) return std::nullopt;
  return scheduled_.begin()->t_ns;
}

std::vector<EdgeNotice> VirtualChip::run_due(std::int64_t now_ns) {
  const std::lock_guard lock(mutex_);
  std::vector<EdgeNotice> notices;
  while (!scheduled_.empty() && scheduled_.begin()->t_ns <= now_ns) {
    const ScheduledStrobe due = *scheduled_.begin();
    scheduled_.erase(scheduled_.begin());
    const unsigned offset = *layout_.strobe;
    if (lines_[offset].stuck) continue;
    const bool level = due.active != layout_.lines[offset].active_low;
    if (level == lines_[offset].level) continue;
    auto more = apply({{offset, level}}, due.t_ns);
    notices.insert(notices.end(), more.begin(), more.end());
  }
  return notices;
}

void VirtualChip::inject(const Fault& fault) {
  const std::lock_guard lock(mutex_);
  switch (fault.kind) {
    case Fault::Kind::kLoseStrobe:
      lose_strobe_at_.insert(fault.count);
      break;
    case Fault::Kind::kStuck: {
      const auto offset = layout_.resolve(fault.line);
      if (!offset) fail("fault '{}': {} has no line '{}'", fault.text, layout_.label, fault.line);
      lines_[*offset].stuck = true;
      break;
    }
    case Fault::Kind::kDropConnection:
      fail("fault '{}' acts on connections: give it to the server, not the chip", fault.text);
  }
  logger("sim")->info("fault armed: {}", fault.text);
}

void VirtualChip::publish(std::vector<TimelineEntry>& entries) {
  if (entries.empty()) return;
  for (const auto& sink : sinks_) sink->record(entries);
  for (auto& entry : entries) timeline_.push_back(std::move(entry));
  while (timeline_.size() > options_.timeline_memory) timeline_.pop_front();
}

std::vector<TimelineEntry> VirtualChip::timeline() const {
  const std::lock_guard lock(mutex_);
  return {timeline_.begin(), timeline_.end()};
}

int VirtualChip::active_value(unsigned offset) const {
  const std::lock_guard lock(mutex_);
  check_offset(offset);
  return active_of(offset) ? 1 : 0;
}

bool VirtualChip::led_lit(int led_id) const {
  const std::lock_guard lock(mutex_);
  for (std::size_t i = 0; i < layout_.lines.size(); ++i) {
    if (layout_.lines[i].role == LineRole::kLed && layout_.lines[i].led_id == led_id) {
      return active_of(static_cast<unsigned>(i));
    }
  }
  for (std::size_t c = 0; c < layout_.chains.size(); ++c) {
    const auto& bits = layout_.chains[c].led_by_bit;
    const auto it = std::find(bits.begin(), bits.end(), led_id);
    if (it != bits.end()) return chains_[c].output(static_cast<int>(it - bits.begin()));
  }
  fail("{}: no LED {} on the virtual chip", layout_.label, led_id);
}

ChipStats VirtualChip::stats() const {
  const std::lock_guard lock(mutex_);
  return stats_;
}

}  // namespace lightstage::sim::gpio
