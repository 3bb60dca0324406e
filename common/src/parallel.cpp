#include "lightstage/common/parallel.hpp"

#include <opencv2/core/utility.hpp>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <system_error>
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

// A call's workers, open to every thread of the process that runs out of
// work of its own: a thread whose share is done, or whose caller waits for
// its helpers, takes a worker not yet started from any open call under the
// same outermost call (a worker of parallel_for takes indices until none
// remain). No thread is added for it, so the limit holds, and work that nests
// unevenly (two tasks side by side, each running its own calls on one thread)
// still keeps every thread busy. Work of another outermost call (another
// thread's command) is never taken: its end would hold up this one's.
struct Job {
  const void* root = nullptr;  // the outermost call's job
  const std::function<void(std::size_t)>* worker = nullptr;
  std::size_t count = 0;
  std::size_t next = 0;  // the next worker to start; guarded by job_mutex
  int running = 0;       // workers started and not finished, and helpers not done; guarded by job_mutex
};

std::mutex job_mutex;
std::condition_variable job_changed;
std::vector<Job*> open_jobs;                      // jobs with workers not yet started
thread_local const void* current_root = nullptr;  // of the outermost call this thread works for

// A worker of an open job under this thread's outermost call, other than
// `except`, claimed (counted running), or null. Call with job_mutex held.
Job* claim_open_job(const Job* except, std::size_t& worker) {
  for (Job* job : open_jobs) {
    if (job == except || job->root != current_root || job->next >= job->count) continue;
    worker = job->next++;
    ++job->running;
    return job;
  }
  return nullptr;
}

// Runs a claimed worker, then the job's next ones until none is left.
void run_claimed(Job& job, std::size_t worker) {
  for (;;) {
    (*job.worker)(worker);
    const std::lock_guard lock(job_mutex);
    --job.running;
    if (job.next >= job.count) {
      if (job.running == 0) job_changed.notify_all();
      return;
    }
    worker = job.next++;
    ++job.running;
  }
}

// Runs workers of open jobs until there are none to start.
void help_open_jobs() {
  for (;;) {
    std::size_t worker = 0;
    Job* job = nullptr;
    {
      const std::lock_guard lock(job_mutex);
      job = claim_open_job(nullptr, worker);
    }
    if (job == nullptr) return;
    run_claimed(*job, worker);
  }
}

// Runs worker(0 .. count-1), worker(0) on the caller's thread, the others on
// helpers (reserve_helpers) and on any thread that runs out of work while
// they wait (Job). Returns when every worker has finished and every helper
// is done. `worker` must not throw.
void run_workers(std::size_t count, const std::function<void(std::size_t)>& worker) {
  const bool outermost = !inside_parallel_work;
  std::vector<std::thread> threads;
  // Reserved before the threads are counted busy: below, only a thread's start can fail.
  threads.reserve(count - 1);
  const auto helpers = static_cast<std::size_t>(reserve_helpers(static_cast<int>(count) - 1));
  inside_parallel_work = true;
  Job job;
  if (outermost) current_root = &job;
  job.root = current_root;
  job.worker = &worker;
  job.count = count;
  // Worker 0 is the caller's, worker h helper h's; the rest go to whichever thread is free first.
  job.next = 1 + helpers;
  // Each worker until it finishes, each helper until it is done.
  job.running = 1 + 2 * static_cast<int>(helpers);
  if (count > 1) {
    const std::lock_guard lock(job_mutex);
    open_jobs.push_back(&job);
    job_changed.notify_all();
  }
  std::size_t started = 0;
  for (std::size_t h = 1; h <= helpers; ++h) {
    count_helper(+1);
    try {
      threads.emplace_back([&job, h] {
        inside_parallel_work = true;
        current_root = job.root;
        run_claimed(job, h);
        help_open_jobs();
        count_helper(-1);
        --busy_threads;
        const std::lock_guard lock(job_mutex);
        if (--job.running == 0) job_changed.notify_all();
      });
    } catch (const std::system_error&) {
      // The system has no thread to give: this helper's worker and the rest run on the threads that are.
      count_helper(-1);
      break;
    }
    started = h;
  }
  if (started < helpers) {
    busy_threads -= static_cast<int>(helpers - started);
    const std::lock_guard lock(job_mutex);
    job.running -= static_cast<int>(helpers - started);  // their workers stay counted until run below
  }
  run_claimed(job, 0);
  for (std::size_t w = started + 1; w <= helpers; ++w) {
    worker(w);
    const std::lock_guard lock(job_mutex);
    --job.running;
  }
  {
    std::unique_lock lock(job_mutex);
    for (;;) {
      if (job.running == 0) break;
      std::size_t other = 0;
      if (Job* open = claim_open_job(&job, other)) {
        lock.unlock();
        run_claimed(*open, other);
        lock.lock();
        continue;
      }
      job_changed.wait(lock);
    }
    if (count > 1) open_jobs.erase(std::find(open_jobs.begin(), open_jobs.end(), &job));
  }
  for (auto& thread : threads) thread.join();
  if (outermost) {
    inside_parallel_work = false;
    current_root = nullptr;
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
