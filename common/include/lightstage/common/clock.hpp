#pragma once
// Time for the sequencer and the GPIO world: nanoseconds on CLOCK_MONOTONIC
// (the clock libgpiod stamps edge events with). Behind an interface so tests
// can run the sequencer on a virtual clock.

#include <cstdint>

namespace lightstage {

class Clock {
 public:
  virtual ~Clock() = default;
  virtual std::int64_t now_ns() const = 0;
  // Sleeps until the absolute time `t_ns` (returns at once if it has passed).
  virtual void sleep_until(std::int64_t t_ns) = 0;
};

// CLOCK_MONOTONIC with clock_nanosleep(TIMER_ABSTIME): deadlines do not drift
// with the time spent working between them.
class MonotonicClock final : public Clock {
 public:
  std::int64_t now_ns() const override;
  void sleep_until(std::int64_t t_ns) override;
};

std::int64_t monotonic_now_ns();

// Nanoseconds as microseconds, for messages and the wire protocol's _us fields.
inline double ns_to_us(std::int64_t ns) { return static_cast<double>(ns) / 1000.0; }

}  // namespace lightstage
