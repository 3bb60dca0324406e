#pragma once
// The virtual gpiochip of lightstage-sim: the rig's lines (chip_layout.hpp),
// who holds each one (consumers), their levels, the timeline of every change
// with the firmware's own timestamps (timeline.hpp), the LEDs lit through
// shift-register chains (shift_register.hpp), an emulated camera strobe and
// injected faults (fault.hpp).
//
// The chip is a plain state machine, safe to call from several threads: it
// never sleeps and never talks to a socket. Emulated strobe edges are
// scheduled in the firmware's clock and applied by run_due(now), which the
// server calls when CLOCK_MONOTONIC reaches them (tests call it with any time).

#include "lightstage/common/gpio.hpp"
#include "lightstage/common/rig.hpp"
#include "lightstage/sim/gpio/chip_layout.hpp"
#include "lightstage/sim/gpio/fault.hpp"
#include "lightstage/sim/gpio/shift_register.hpp"
#include "lightstage/sim/gpio/timeline.hpp"

#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <vector>

namespace lightstage::sim::gpio {

using ClientId = std::uint64_t;  // one per connection; 0 = nobody

struct VirtualChipOptions {
  // Emulate the camera's exposure-active output on the strobe line: on the
  // trigger's active edge at t0, active at t0 + delay, inactive at
  // t0 + delay + exposure. Off when the rig has no strobe line.
  bool strobe = true;
  std::int64_t strobe_delay_ns = 100'000;
  std::int64_t strobe_exposure_ns = 10'000'000;
  // Timeline entries kept in memory for timeline() (the oldest are dropped).
  std::size_t timeline_memory = 250'000;

  // Throws InputError naming the option and its value.
  void check() const;
};

// Defaults for a rig: strobe on iff the rig has a strobe line, exposure = the
// rig camera's exposure_us.
VirtualChipOptions chip_options_for(const Rig& rig);

// An edge for the client that requested the line for edge events.
struct EdgeNotice {
  ClientId client = 0;
  lightstage::gpio::EdgeEvent edge;
};

struct ChipStats {
  int triggers = 0;          // active trigger edges seen
  int strobes = 0;           // exposures scheduled
  int strobes_lost = 0;      // triggers skipped by a lose-strobe fault
  int triggers_ignored = 0;  // triggers during an exposure (the camera was busy)
};

class VirtualChip {
 public:
  VirtualChip(ChipLayout layout, VirtualChipOptions options);

  // Receives every batch of timeline entries from now on (the --timeline
  // file; later the virtual camera).
  void add_timeline_sink(std::shared_ptr<TimelineSink> sink);

  lightstage::gpio::ChipInfo info() const;
  const ChipLayout& layout() const { return layout_; }
  const VirtualChipOptions& options() const { return options_; }

  // A connection arrives / leaves; leaving releases its lines (their levels stay).
  ClientId connect();
  void disconnect(ClientId client);

  // Errors are gpio::GpioError naming the line (and its consumer when busy).
  // `active_low` and `initial` are per offset or empty; `t_ns` stamps the
  // initial levels of outputs (0: now).
  void request_lines(ClientId client, std::span<const unsigned> offsets, bool output,
                     const std::string& consumer, std::span<const bool> active_low,
                     std::span<const int> initial, std::int64_t t_ns);
  // Logical values (1 = active as requested) on lines the client holds as outputs.
  // Returns edges for clients watching lines that changed.
  std::vector<EdgeNotice> set_values(ClientId client, std::span<const unsigned> offsets,
                                     std::span<const int> values, std::int64_t t_ns);
  void release_lines(ClientId client, std::span<const unsigned> offsets);

  // lose-strobe and stuck; a drop-connection fault belongs to the server
  // (InputError here). Throws InputError for a line the chip does not have.
  void inject(const Fault& fault);

  // The emulated camera: when the next scheduled strobe change is due, and
  // applying every change due at `now_ns` (edges for whoever watches the strobe).
  std::optional<std::int64_t> next_due_ns() const;
  std::vector<EdgeNotice> run_due(std::int64_t now_ns);
  // The virtual camera's exposure changed: later strobes last this long.
  void set_strobe_exposure_ns(std::int64_t exposure_ns);

  // Observations, for tests and the virtual camera.
  std::vector<TimelineEntry> timeline() const;
  int active_value(unsigned offset) const;  // 1 = active as the rig wires it
  bool led_lit(int led_id) const;
  ChipStats stats() const;

 private:
  struct LineState {
    bool level = false;  // electrical level
    ClientId owner = 0;
    std::string consumer;
    bool output = false;
    bool request_active_low = false;
    bool stuck = false;
  };
  struct ScheduledStrobe {
    std::int64_t t_ns;
    bool active;
    bool operator<(const ScheduledStrobe& other) const { return t_ns < other.t_ns; }
  };
  struct LevelChange {
    unsigned offset;
    bool level;
  };

  std::string describe_line(unsigned offset) const;  // line 17 "LED17"
  void check_offset(unsigned offset) const;
  bool active_of(unsigned offset) const;
  // Applies level changes made at once at `t_ns`: timeline, chains, trigger, edges.
  std::vector<EdgeNotice> apply(const std::vector<LevelChange>& changes, std::int64_t t_ns);
  void on_trigger(std::int64_t t_ns);
  void publish(std::vector<TimelineEntry>& entries);

  const ChipLayout layout_;
  const VirtualChipOptions options_;
  std::int64_t strobe_exposure_ns_;  // options_.strobe_exposure_ns until the camera changes it
  mutable std::mutex mutex_;
  std::vector<LineState> lines_;
  std::vector<ShiftRegisterChainModel> chains_;
  std::vector<std::shared_ptr<TimelineSink>> sinks_;
  std::deque<TimelineEntry> timeline_;
  std::multiset<ScheduledStrobe> scheduled_;
  std::set<int> lose_strobe_at_;  // trigger numbers, counting from 1
  std::int64_t camera_busy_until_ns_ = 0;
  ChipStats stats_;
  ClientId next_client_ = 1;
};

}  // namespace lightstage::sim::gpio
