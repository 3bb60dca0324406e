#pragma once
// Spreading independent work over std::threads, the first worker on the
// caller's thread. Two ways to split it:
// - parallel_chunks: contiguous, in-order ranges, one per thread, each with
//   its chunk number, so per-chunk partial results can be merged in chunk
//   order and give the same total for a given thread count;
// - parallel_for: indices handed out one at a time, for work whose cost varies
//   by index (image rows); results must not depend on which thread ran which
//   index. parallel_invoke hands out different tasks the same way.
// A call made from inside another's work (nested) starts on the threads of
// the limit (resolve_threads(0)) that no work is running on at its start, and
// on its caller's alone when none is free: work may nest without the process
// ever running more threads at once than the limit, or than the outermost
// call asked for if that is more. A thread that runs out of work (a helper
// whose share is done, a caller waiting for its helpers) then takes workers
// not yet started of any call under the same outermost call, so work that
// nests unevenly still keeps every thread busy; work of another outermost
// call (another thread's command) is never taken. Hence:
// - nested work must not wait for work of the same call to start (it may run
//   after it, on the same thread);
// - a body must not hold a lock, or thread-local scratch it is using, across a
//   parallel call: while the call waits, its thread may run other work of the
//   same command, that body's again included;
// - a call returns once its helpers are done with the other work they took.

#include <cstddef>
#include <functional>
#include <vector>

namespace lightstage {

// `requested` threads; when it is 0 or less, the limit of the innermost
// ThreadLimit in scope, else the hardware concurrency (at least 1).
int resolve_threads(int requested);

// Caps the work that asks for "all cores" (threads 0), here and in OpenCV
// (each of its parallel calls), while it lives: a command's --threads holds
// for every stage it runs (decoding, solving, writing, the report) without
// each call being told. 0 or less leaves the limit as it was. The limit is
// the process's: make it on the thread that runs the command, before its
// parallel work starts, and let it end after (limits nest, the destructor
// restores the one before); jobs side by side cannot hold different limits.
class ThreadLimit {
 public:
  explicit ThreadLimit(int threads);
  ~ThreadLimit();
  ThreadLimit(const ThreadLimit&) = delete;
  ThreadLimit& operator=(const ThreadLimit&) = delete;

 private:
  int previous_ = 0;
  int previous_opencv_ = 0;
  bool set_ = false;
};

// The most threads that ran work of the functions below at once (the caller's
// counted once, however deeply calls nest) since the last reset: how tests see
// that --threads is kept.
int parallel_peak_threads();
void reset_parallel_peak_threads();

// Calls body(chunk, begin, end) for `chunks` contiguous, in-order ranges that
// cover [0, count), each on its own thread as far as threads are free (the
// rest on whichever comes free first). Returns the number of chunks used
// (<= resolved threads, >= 1; one empty chunk when count is 0). Every chunk
// runs to its end; an exception from a body is rethrown on the caller's thread
// once all have finished (the first one, by chunk order).
std::size_t parallel_chunks(
    std::size_t count, int threads,
    const std::function<void(std::size_t chunk, std::size_t begin, std::size_t end)>& body);

// Calls body(i) once for every i in [0, n) (none when n <= 0) on up to
// `threads` threads (resolve_threads). After an exception no further index is
// started; the first exception thrown is rethrown on the caller's thread.
void parallel_for(int n, int threads, const std::function<void(int)>& body);

// Runs every task once, side by side on up to `threads` threads (a task is
// handed to the next free thread). Every task runs to its end; the exception
// of the first failed task, by task order, is rethrown on the caller's thread
// (so the error a user sees does not depend on timing).
void parallel_invoke(const std::vector<std::function<void()>>& tasks, int threads);

}  // namespace lightstage
