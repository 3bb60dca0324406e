#pragma once
// A tiny parallel_for over [0, n) with std::thread: indices are handed out one
// at a time from an atomic counter, so results must not depend on which
// thread runs which index (the renderer writes one row per index).

#include <functional>

namespace lightstage::sim {

// threads <= 0: hardware concurrency. Rethrows the first exception thrown by `body`.
void parallel_for(int n, int threads, const std::function<void(int)>& body);

// The thread count `threads` resolves to.
int resolve_threads(int threads);

}  // namespace lightstage::sim
