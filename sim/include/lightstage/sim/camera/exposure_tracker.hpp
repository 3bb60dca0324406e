#pragma once
// What the virtual camera needs from the virtual gpiochip: when each LED was
// lit and when the trigger fired. Fed as a timeline sink (every line change,
// stamped with the firmware's clock), it answers "what share of the window
// [t0, t1] was each LED lit?" — the weights the renderer lights the scene with.

#include "lightstage/sim/gpio/timeline.hpp"

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace lightstage::sim {

// How long after a window ends the chip may still be receiving changes stamped
// inside it (the firmware stamps, then sends): a camera waits this long before
// reading the window, and at most the second before it takes what it has.
inline constexpr std::int64_t kWindowSettleNs = 5'000'000, kWindowCatchUpNs = 50'000'000;

// A CLOCK_MONOTONIC time (the chip's stamps) as a steady_clock time point: the same clock on Linux.
inline std::chrono::steady_clock::time_point steady_at(std::int64_t t_ns) {
  return std::chrono::steady_clock::time_point(std::chrono::nanoseconds(t_ns));
}

class ExposureTracker final : public gpio::TimelineSink {
 public:
  // `trigger_line` is the chip's name for the camera trigger ("" = none);
  // `on_trigger` is called with the time of each active trigger edge (under
  // the chip's lock: it must only queue the work).
  ExposureTracker(std::string trigger_line, std::function<void(std::int64_t)> on_trigger);

  void record(std::span<const gpio::TimelineEntry> entries) override;

  // (LED id, share of [t0_ns, t1_ns] it was lit) for every LED lit at all in the window.
  std::vector<std::pair<int, double>> lit_shares(std::int64_t t0_ns, std::int64_t t1_ns) const;
  // The newest time any change was stamped with (0 before the first).
  std::int64_t latest_ns() const;
  // Forgets changes that ended before `t_ns` (the camera never looks back that far).
  void forget_before(std::int64_t t_ns);

 private:
  struct Change {
    std::int64_t t_ns;
    bool lit;
  };

  std::string trigger_line_;
  std::function<void(std::int64_t)> on_trigger_;
  mutable std::mutex mutex_;
  std::map<int, std::vector<Change>> changes_;  // by LED id, in time order
  std::int64_t latest_ns_ = 0;
};

}  // namespace lightstage::sim
