#pragma once
// Wall time for the timings a command reports.

#include <chrono>

namespace lightstage {

// Seconds on the steady clock since `start`.
inline double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace lightstage
