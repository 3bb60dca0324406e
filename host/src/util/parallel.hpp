#pragma once
// Splitting index ranges over std::threads. Every index is processed by
// exactly one call, so work that is independent per index gives the same
// result for any number of threads.

#include <cstddef>
#include <functional>

namespace lightstage::util {

// `requested` threads, or the hardware concurrency when it is 0 (at least 1).
int resolve_threads(int requested);

// Calls body(chunk, begin, end) for `chunks` contiguous, in-order ranges that
// cover [0, count), each on its own thread (the first on the caller's).
// Returns the number of chunks used (<= threads, >= 1). Exceptions from a
// body are rethrown on the caller's thread (the first one, by chunk order).
std::size_t parallel_chunks(
    std::size_t count, int threads,
    const std::function<void(std::size_t chunk, std::size_t begin, std::size_t end)>& body);

}  // namespace lightstage::util
