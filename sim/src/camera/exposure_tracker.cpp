#include "lightstage/sim/camera/exposure_tracker.hpp"

#include <algorithm>

namespace lightstage::sim {

ExposureTracker::ExposureTracker(std::string trigger_line, std::function<void(std::int64_t)> on_trigger)
    : trigger_line_(std::move(trigger_line)), on_trigger_(std::move(on_trigger)) {}

void ExposureTracker::record(std::span<const gpio::TimelineEntry> entries) {
  std::vector<std::int64_t> triggers;
  {
    const std::lock_guard lock(mutex_);
    for (const auto& e : entries) {
      latest_ns_ = std::max(latest_ns_, e.t_ns);
      if (e.led >= 0) {
        auto& list = changes_[e.led];
        const Change change{e.t_ns, e.value != 0};
        // Keep time order even if a batch arrives slightly out of order.
        const auto at = std::upper_bound(list.begin(), list.end(), change.t_ns,
                                         [](std::int64_t t, const Change& c) { return t < c.t_ns; });
        list.insert(at, change);
      } else if (!trigger_line_.empty() && e.line == trigger_line_ && e.value != 0) {
        triggers.push_back(e.t_ns);
      }
    }
  }
  if (on_trigger_) {
    for (const std::int64_t t : triggers) on_trigger_(t);
  }
}

std::vector<std::pair<int, double>> ExposureTracker::lit_shares(std::int64_t t0_ns,
                                                                std::int64_t t1_ns) const {
  std::vector<std::pair<int, double>> shares;
  if (t1_ns <= t0_ns) return shares;
  const std::lock_guard lock(mutex_);
  for (const auto& [led, list] : changes_) {
    std::int64_t lit_ns = 0;
    bool lit = false;
    std::int64_t since = t0_ns;
    for (const Change& c : list) {
      if (c.t_ns >= t1_ns) break;
      if (c.t_ns > t0_ns && lit) lit_ns += c.t_ns - since;
      lit = c.lit;
      since = std::max(c.t_ns, t0_ns);
    }
    if (lit) lit_ns += t1_ns - since;
    if (lit_ns > 0)
      shares.emplace_back(led, static_cast<double>(lit_ns) / static_cast<double>(t1_ns - t0_ns));
  }
  return shares;
}

std::int64_t ExposureTracker::latest_ns() const {
  const std::lock_guard lock(mutex_);
  return latest_ns_;
}

void ExposureTracker::forget_before(std::int64_t t_ns) {
  const std::lock_guard lock(mutex_);
  for (auto& [led, list] : changes_) {
    // Keep the last change at or before t_ns: it says whether the LED was lit at t_ns.
    auto first_after = std::upper_bound(list.begin(), list.end(), t_ns,
                                        [](std::int64_t t, const Change& c) { return t < c.t_ns; });
    if (first_after - list.begin() > 1) list.erase(list.begin(), first_after - 1);
  }
}

}  // namespace lightstage::sim
