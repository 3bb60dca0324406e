#pragma once
// The firmware's hard limits on LED on-time. Whatever the host asks, an LED may
// stay on at most `max_on_us` at a stretch, and within any sliding window of
// `duty_window_us` it may be on at most `max_duty` of the time (rig.hpp,
// LedLimits). The sequencer asks before it switches an LED on and reports
// what it actually did afterwards; times are microseconds on one monotonic clock.

#include "lightstage/common/rig.hpp"

#include <deque>
#include <map>
#include <string>

namespace lightstage::firmware {

struct SafetyVerdict {
  bool allowed = false;
  std::string reason;  // empty when allowed; names the LED, the limit and the numbers otherwise
};

class LedSafety {
 public:
  explicit LedSafety(const Rig& rig);

  // May `led_id` be switched on at `start_us` for `duration_us`?
  SafetyVerdict check(int led_id, double start_us, double duration_us) const;

  // Records that `led_id` was on over [on_us, off_us].
  void record(int led_id, double on_us, double off_us);

  // On-time of `led_id` inside the window (end_us - duty_window_us, end_us].
  double on_time_in_window(int led_id, double end_us) const;

  // The longest pulse `led_id` may start at `start_us` (0 if none): what
  // check() allows, found by bisection (the on-time a pulse adds grows with
  // its length faster than old history leaves the window).
  double allowed_on_us(int led_id, double start_us) const;

  const LedLimits& limits(int led_id) const { return state(led_id).limits; }

 private:
  struct Interval {
    double on_us;
    double off_us;
  };
  struct LedState {
    LedLimits limits;
    std::deque<Interval> history;  // oldest first, pruned to one duty window
  };
  const LedState& state(int led_id) const;

  std::map<int, LedState> leds_;
};

}  // namespace lightstage::firmware
