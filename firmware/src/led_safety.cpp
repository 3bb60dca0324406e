#include "lightstage/firmware/led_safety.hpp"

#include "lightstage/common/error.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace lightstage::firmware {

LedSafety::LedSafety(const Rig& rig) {
  for (const Led& led : rig.leds) leds_[led.id].limits = led.limits;
}

const LedSafety::LedState& LedSafety::state(int led_id) const {
  const auto it = leds_.find(led_id);
  if (it == leds_.end()) fail("no LED with id {} in the rig", led_id);
  return it->second;
}

double LedSafety::on_time_in_window(int led_id, double end_us) const {
  const LedState& led = state(led_id);
  const double window_start = end_us - led.limits.duty_window_us;
  double total = 0;
  for (const Interval& interval : led.history) {
    const double from = std::max(interval.on_us, window_start);
    const double to = std::min(interval.off_us, end_us);
    if (to > from) total += to - from;
  }
  return total;
}

SafetyVerdict LedSafety::check(int led_id, double start_us, double duration_us) const {
  const auto it = leds_.find(led_id);
  if (it == leds_.end()) return {false, fmt::format("LED {}: not in the rig", led_id)};
  const LedLimits& limits = it->second.limits;
  if (!(duration_us >= 0)) return {false, fmt::format("LED {}: invalid on-time {} us", led_id, duration_us)};
  if (duration_us > limits.max_on_us) {
    return {false, fmt::format("LED {}: on-time {:.0f} us exceeds max_on_us {:.0f} us", led_id, duration_us,
                               limits.max_on_us)};
  }
  // The window ending when this pulse ends holds the most on-time it can add to.
  const double end_us = start_us + duration_us;
  const double budget = limits.max_duty * limits.duty_window_us;
  const double used = on_time_in_window(led_id, end_us) + std::min(duration_us, limits.duty_window_us);
  if (used > budget) {
    return {false, fmt::format("LED {}: {:.0f} us on within {:.0f} us would exceed max_duty {} ({:.0f} us)",
                               led_id, used, limits.duty_window_us, limits.max_duty, budget)};
  }
  return {true, {}};
}

double LedSafety::allowed_on_us(int led_id, double start_us) const {
  const LedLimits& limits = state(led_id).limits;
  if (!check(led_id, start_us, 0).allowed) return 0;
  if (check(led_id, start_us, limits.max_on_us).allowed) return limits.max_on_us;
  double allowed = 0;
  double refused = limits.max_on_us;
  for (int i = 0; i < 48 && refused - allowed > 1e-3; ++i) {
    const double middle = 0.5 * (allowed + refused);
    (check(led_id, start_us, middle).allowed ? allowed : refused) = middle;
  }
  return allowed;
}

void LedSafety::record(int led_id, double on_us, double off_us) {
  auto it = leds_.find(led_id);
  if (it == leds_.end()) fail("no LED with id {} in the rig", led_id);
  LedState& led = it->second;
  led.history.push_back({on_us, std::max(on_us, off_us)});
  while (!led.history.empty() && led.history.front().off_us < off_us - led.limits.duty_window_us) {
    led.history.pop_front();
  }
}

}  // namespace lightstage::firmware
