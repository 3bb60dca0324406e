// The gpiod: backend over libgpiod 1.6's C++ binding (libgpiodcxx). This is the
// only file that knows libgpiod's v1 API: the chip lookup, bulk line requests
// (at most 64 lines each), and line events. Moving to libgpiod 2 means
// rewriting this file against gpiod::chip::prepare_request() / line_request.
#include "lightstage/hw/gpiod_chip.hpp"

#include <fmt/format.h>

#include <algorithm>

#ifdef LIGHTSTAGE_HAVE_GPIOD
#include "lightstage/common/clock.hpp"

#include <gpiod.hpp>

#include <chrono>
#include <system_error>
#endif

namespace lightstage::hw {

std::vector<std::pair<std::size_t, std::size_t>> bulk_ranges(std::size_t count, std::size_t max_per_bulk) {
  std::vector<std::pair<std::size_t, std::size_t>> ranges;
  if (max_per_bulk == 0) return ranges;
  for (std::size_t first = 0; first < count; first += max_per_bulk) {
    ranges.emplace_back(first, std::min(max_per_bulk, count - first));
  }
  return ranges;
}

#ifndef LIGHTSTAGE_HAVE_GPIOD

std::unique_ptr<gpio::Chip> open_gpiod_chip(const std::string& chip_spec) {
  throw gpio::GpioError(fmt::format(
      "gpiod:{}: this build has no libgpiod backend (install libgpiod-dev and reconfigure)", chip_spec));
}

#else

namespace {

// "gpiochip0 (label "pinctrl-bcm2711", 58 lines), ..." or "none".
std::string list_chips() {
  std::string list;
  try {
    for (const auto& chip : ::gpiod::make_chip_iter()) {
      if (!list.empty()) list += ", ";
      list += fmt::format("{} (label \"{}\", {} lines)", chip.name(), chip.label(), chip.num_lines());
    }
  } catch (const std::system_error& e) {
    return fmt::format("cannot list /dev/gpiochip*: {}", e.what());
  }
  return list.empty() ? "none" : list;
}

::gpiod::chip open_chip(const std::string& spec) {
  if (spec.empty()) {
    throw gpio::GpioError("gpiod: names no chip (use gpiod:/dev/gpiochip0, gpiod:LABEL or gpiod:LINE_NAME)");
  }
  // Path, name, label or number, in libgpiod's lookup order.
  try {
    return ::gpiod::chip(spec, ::gpiod::chip::OPEN_LOOKUP);
  } catch (const std::system_error&) {
  }
  // A chip carrying a line of that name (boards keep line names, not chip numbers).
  try {
    for (const auto& chip : ::gpiod::make_chip_iter()) {
      if (chip.find_line(spec)) return chip;
    }
  } catch (const std::system_error&) {
  }
  throw gpio::GpioError(fmt::format(
      "gpiod:{}: no GPIO chip with that path, name, label or number, and no chip has a line named \"{}\" "
      "(chips on this machine: {})",
      spec, spec, list_chips()));
}

class GpiodOutputLines final : public gpio::OutputLines {
 public:
  struct Bulk {
    ::gpiod::line_bulk lines;
    std::vector<std::size_t> positions;  // index into the caller's request order
  };

  GpiodOutputLines(std::vector<Bulk> bulks, std::size_t count, std::string where)
      : bulks_(std::move(bulks)), count_(count), where_(std::move(where)) {}

  ~GpiodOutputLines() override {
    for (auto& bulk : bulks_) {
      try {
        bulk.lines.release();
      } catch (const std::system_error&) {
        // Releasing can only fail if the chip vanished; nothing left to do.
      }
    }
  }

  // One set_values() per bulk: lines in different bulks switch a few
  // microseconds apart, lines of one bulk together.
  void set(std::span<const int> values, std::int64_t /*t_ns*/) override {
    if (values.size() != count_) {
      throw gpio::GpioError(fmt::format("{}: {} values for {} lines", where_, values.size(), count_));
    }
    try {
      for (auto& bulk : bulks_) {
        std::vector<int> bulk_values;
        bulk_values.reserve(bulk.positions.size());
        for (std::size_t position : bulk.positions) bulk_values.push_back(values[position] ? 1 : 0);
        bulk.lines.set_values(bulk_values);
      }
    } catch (const std::system_error& e) {
      throw gpio::GpioError(fmt::format("{}: setting line values failed: {}", where_, e.what()));
    }
  }

  std::size_t size() const override { return count_; }

 private:
  std::vector<Bulk> bulks_;
  std::size_t count_;
  std::string where_;
};

class GpiodEdgeInput final : public gpio::EdgeInput {
 public:
  GpiodEdgeInput(::gpiod::line line, std::string where) : line_(std::move(line)), where_(std::move(where)) {}
  ~GpiodEdgeInput() override {
    try {
      line_.release();
    } catch (const std::system_error&) {
    }
  }

  // Event timestamps: the v1 uAPI stamps events with CLOCK_MONOTONIC since
  // Linux 5.7 (CLOCK_REALTIME before), the clock the sequencer runs on.
  std::optional<gpio::EdgeEvent> wait_until(std::int64_t deadline_ns) override {
    try {
      const std::int64_t left = std::max<std::int64_t>(0, deadline_ns - monotonic_now_ns());
      if (!line_.event_wait(std::chrono::nanoseconds(left))) return std::nullopt;
      const ::gpiod::line_event event = line_.event_read();
      return gpio::EdgeEvent{line_.offset(), event.event_type == ::gpiod::line_event::RISING_EDGE,
                             static_cast<std::int64_t>(event.timestamp.count())};
    } catch (const std::system_error& e) {
      throw gpio::GpioError(fmt::format("{}: reading edge events failed: {}", where_, e.what()));
    }
  }

  void drain() override {
    while (wait_until(0)) {
    }
  }

 private:
  ::gpiod::line line_;
  std::string where_;
};

class GpiodChip final : public gpio::Chip {
 public:
  GpiodChip(::gpiod::chip chip, std::string spec) : chip_(std::move(chip)), spec_(std::move(spec)) {}

  gpio::ChipInfo info() const override {
    gpio::ChipInfo info;
    try {
      info.label = chip_.label();
      for (unsigned offset = 0; offset < chip_.num_lines(); ++offset) {
        const ::gpiod::line line = chip_.get_line(offset);
        line.update();  // the binding caches line info; the consumer may have changed
        info.line_names.push_back(line.name());
        info.consumers.push_back(line.is_used() ? (line.consumer().empty() ? "kernel" : line.consumer())
                                                : "");
      }
    } catch (const std::system_error& e) {
      throw gpio::GpioError(fmt::format("gpiod:{}: reading line info failed: {}", spec_, e.what()));
    }
    return info;
  }

  std::unique_ptr<gpio::OutputLines> request_outputs(std::span<const unsigned> offsets,
                                                     std::span<const bool> active_low,
                                                     std::span<const int> initial,
                                                     const std::string& consumer) override {
    if (!active_low.empty() && active_low.size() != offsets.size()) {
      throw gpio::GpioError(fmt::format("gpiod:{}: {} active_low flags for {} lines", spec_,
                                        active_low.size(), offsets.size()));
    }
    if (!initial.empty() && initial.size() != offsets.size()) {
      throw gpio::GpioError(
          fmt::format("gpiod:{}: {} initial values for {} lines", spec_, initial.size(), offsets.size()));
    }
    // One bulk request carries one set of flags, so active-low and
    // active-high lines go to separate bulks, each split at 64 lines.
    std::vector<GpiodOutputLines::Bulk> bulks;
    // Bulks already requested are released again when a later one fails.
    const auto release_all = [&bulks] {
      for (auto& bulk : bulks) {
        try {
          bulk.lines.release();
        } catch (const std::system_error&) {
        }
      }
    };
    try {
      for (const bool low : {false, true}) {
        std::vector<std::size_t> positions;
        for (std::size_t i = 0; i < offsets.size(); ++i) {
          if ((!active_low.empty() && active_low[i]) == low) positions.push_back(i);
        }
        for (const auto& [first, count] : bulk_ranges(positions.size())) {
          GpiodOutputLines::Bulk bulk;
          std::vector<int> defaults;
          for (std::size_t k = first; k < first + count; ++k) {
            const std::size_t position = positions[k];
            bulk.lines.append(free_line(offsets[position]));
            bulk.positions.push_back(position);
            defaults.push_back(!initial.empty() && initial[position] ? 1 : 0);
          }
          ::gpiod::line_request request{consumer, ::gpiod::line_request::DIRECTION_OUTPUT, {}};
          if (low) request.flags = ::gpiod::line_request::FLAG_ACTIVE_LOW;
          try {
            bulk.lines.request(request, defaults);
          } catch (const std::system_error& e) {
            throw gpio::GpioError(
                fmt::format("gpiod:{}: requesting {} output line(s) from offset {} failed: {}", spec_, count,
                            offsets[positions[first]], e.what()));
          }
          bulks.push_back(std::move(bulk));
        }
      }
    } catch (...) {
      release_all();
      throw;
    }
    return std::make_unique<GpiodOutputLines>(std::move(bulks), offsets.size(), "gpiod:" + spec_);
  }

  std::unique_ptr<gpio::EdgeInput> request_edges(unsigned offset, bool active_low,
                                                 const std::string& consumer) override {
    ::gpiod::line line = free_line(offset);
    ::gpiod::line_request request{consumer, ::gpiod::line_request::EVENT_BOTH_EDGES, {}};
    if (active_low) request.flags = ::gpiod::line_request::FLAG_ACTIVE_LOW;
    try {
      line.request(request);
    } catch (const std::system_error& e) {
      throw gpio::GpioError(
          fmt::format("gpiod:{}: requesting edge events on line {} failed: {}", spec_, offset, e.what()));
    }
    return std::make_unique<GpiodEdgeInput>(std::move(line), fmt::format("gpiod:{} line {}", spec_, offset));
  }

 private:
  // The line at `offset`, which must exist and be free.
  ::gpiod::line free_line(unsigned offset) const {
    if (offset >= chip_.num_lines()) {
      throw gpio::GpioError(
          fmt::format("gpiod:{}: no line {} (the chip has {} lines)", spec_, offset, chip_.num_lines()));
    }
    try {
      ::gpiod::line line = chip_.get_line(offset);
      line.update();
      if (line.is_used()) {
        throw gpio::GpioError(fmt::format("gpiod:{}: line {} (\"{}\") is busy, used by \"{}\"", spec_, offset,
                                          line.name(), line.consumer()));
      }
      return line;
    } catch (const std::system_error& e) {
      throw gpio::GpioError(fmt::format("gpiod:{}: line {}: {}", spec_, offset, e.what()));
    }
  }

  ::gpiod::chip chip_;
  std::string spec_;
};

}  // namespace

std::unique_ptr<gpio::Chip> open_gpiod_chip(const std::string& chip_spec) {
  return std::make_unique<GpiodChip>(open_chip(chip_spec), chip_spec);
}

#endif  // LIGHTSTAGE_HAVE_GPIOD

}  // namespace lightstage::hw
