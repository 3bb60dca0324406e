#include "lightstage/common/parallel.hpp"

#include <opencv2/core/utility.hpp>

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace lightstage {
namespace {

std::atomic<int> thread_limit{0};  // 0: the hardware's
std::atomic<int> helper_threads{0};
std::atomic<int> peak_helper_threads{0};
// Threads running parallel work now: each outermost caller and every helper.
std::atomic<int> busy_threads{0};
thread_local bool inside_parallel_work = false;

void count_helper(int change) {
  const int now = helper_threads.fetch_add(change) + change;
  int peak = peak_helper_threads.load();
  while (now > peak && !peak_helper_threads.compare_exchange_weak(peak, now)) {
  }
}

int limit_or_hardware() {
  if (const int limit = thread_limit.load(); limit > 0) return limit;
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

// Helpers a call wanting `wanted` may start. The outermost call starts them
// all; a call made from parallel work takes only the threads of the limit
// that no work is running on, so nesting never runs more threads at once
// than the limit (or the outermost call's own count, if larger).
int reserve_helpers(int wanted) {
  if (!inside_parallel_work) {
    busy_threads += 1 + wanted;
    return wanted;
  }
  const int limit = limit_or_hardware();
  int busy = busy_threads.load();
  int granted = 0;
  do {
    granted = std::clamp(limit - busy, 0, wanted);
  } while (granted > 0 && !busy_threads.compare_exchange_weak(busy, busy + granted));
  return granted;
}

// Runs worker(0 .. count-1), worker(0) on the caller's thread, the others on
// helpers (reserve_helpers): with fewer helpers than workers, a thread runs
// several workers one after the other. Joins them all. `worker` must not throw.
void run_workers(std::size_t count, const std::function<void(std::size_t)>& worker) {
  const bool outermost = !inside_parallel_work;
  std::vector<std::thread> threads;
  // Reserved before the threads are counted busy: below, only a thread's start can throw.
  threads.reserve(count - 1);
  const auto helpers = static_cast<std::size_t>(reserve_helpers(static_cast<int>(count) - 1));
  const std::size_t stride = helpers + 1;
  const auto run_share = [&worker, count, stride](std::size_t first) {
    inside_parallel_work = true;
    for (std::size_t w = first; w < count; w += stride) worker(w);
  };
  for (std::size_t h = 1; h <= helpers; ++h) {
    count_helper(+1);
    threads.emplace_back([&run_share, h] {
      run_share(h);
      count_helper(-1);
      --busy_threads;
    });
  }
  run_share(0);
  for (auto& thread : threads) thread.join();
  if (outermost) {
    inside_parallel_work = false;
    --busy_threads;
  }
}

}  // namespace

int resolve_threads(int requested) { return requested > 0 ? requested : limit_or_hardware(); }

ThreadLimit::ThreadLimit(int threads) {
  if (threads <= 0) return;
  previous_ = thread_limit.exchange(threads);
  previous_opencv_ = cv::getNumThreads();
  cv::setNumThreads(threads);
  set_ = true;
}

ThreadLimit::~ThreadLimit() {
  if (!set_) return;
  thread_limit = previous_;
  cv::setNumThreads(previous_opencv_);
}

int parallel_peak_threads() { return 1 + peak_helper_threads.load(); }

void reset_parallel_peak_threads() { peak_helper_threads = helper_threads.load(); }

std::size_t parallel_chunks(std::size_t count, int threads,
                            const std::function<void(std::size_t, std::size_t, std::size_t)>& body) {
  const std::size_t chunks = std::max<std::size_t>(
      1, std::min<std::size_t>(static_cast<std::size_t>(resolve_threads(threads)), count));
  std::vector<std::exception_ptr> errors(chunks);
  run_workers(chunks, [&](std::size_t chunk) {
    try {
      body(chunk, count * chunk / chunks, count * (chunk + 1) / chunks);
    } catch (...) {
      errors[chunk] = std::current_exception();
    }
  });
  for (const auto& error : errors) {
    if (error) std::rethrow_exception(error);
  }
  return chunks;
}

void parallel_for(int n, int threads, const std::function<void(int)>& body) {
  const int workers = std::min(resolve_threads(threads), std::max(n, 1));
  std::atomic<int> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  run_workers(static_cast<std::size_t>(workers), [&](std::size_t) {
    for (int i = next++; i < n; i = next++) {
      try {
        body(i);
      } catch (...) {
        const std::lock_guard lock(error_mutex);
        if (!error) error = std::current_exception();
        next = n;  // stop handing out work
      }
    }
  });
  if (error) std::rethrow_exception(error);
}

void parallel_invoke(const std::vector<std::function<void()>>& tasks, int threads) {
  std::vector<std::exception_ptr> errors(tasks.size());
  parallel_for(static_cast<int>(tasks.size()), threads, [&](int i) {
    const auto task = static_cast<std::size_t>(i);
    try {
      tasks[task]();
    } catch (...) {
      errors[task] = std::current_exception();
    }
  });
  for (const auto& error : errors) {
    if (error) std::rethrow_exception(error);
  }
}

}  // namespace lightstage
