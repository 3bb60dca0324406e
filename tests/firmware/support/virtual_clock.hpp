#pragma once
// A clock for deterministic sequencer tests: time stands still until someone
// sleeps, and sleep_until() jumps straight to the deadline (plus an optional
// oversleep, to play a late wake-up).

#include "lightstage/common/clock.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <thread>

namespace lightstage::firmware::testing {

class VirtualClock final : public Clock {
 public:
  explicit VirtualClock(std::int64_t start_ns = 1'000'000'000) : now_(start_ns) {}

  std::int64_t now_ns() const override { return now_; }
  void sleep_until(std::int64_t t_ns) override {
    ++sleeps_;
    if (t_ns <= now_) return;
    now_ = t_ns + oversleep_ns_;
  }
  // Moves time forward by `ns` without a sleep (work that takes time).
  void advance(std::int64_t ns) { now_ += ns; }
  // Every sleep that has to wait wakes this late.
  void set_oversleep(std::int64_t ns) { oversleep_ns_ = ns; }
  int sleeps() const { return sleeps_; }

 private:
  std::atomic<std::int64_t> now_;
  std::atomic<std::int64_t> oversleep_ns_{0};
  std::atomic<int> sleeps_{0};
};

// A clock only the test moves (advance()), for code running on another
// thread: sleep_until() waits until the test has moved time past the
// deadline, but also returns after a millisecond of real time so that the
// caller's loop can look at its stop flag (the firmware's waits all loop
// until their deadline has really passed).
class ManualClock final : public Clock {
 public:
  explicit ManualClock(std::int64_t start_ns = 1'000'000'000) : now_(start_ns) {}

  std::int64_t now_ns() const override { return now_; }
  void sleep_until(std::int64_t t_ns) override {
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::milliseconds(1);
    while (now_ < t_ns && std::chrono::steady_clock::now() < give_up) {
      std::this_thread::sleep_for(std::chrono::microseconds(100));
    }
  }
  void advance(std::int64_t ns) { now_ += ns; }

 private:
  std::atomic<std::int64_t> now_;
};

}  // namespace lightstage::firmware::testing
