#include "lightstage/common/parallel.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <opencv2/core/utility.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <functional>
#include <latch>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <tuple>
#include <vector>

namespace lightstage {
namespace {

using ::testing::ElementsAre;

TEST(ResolveThreads, KeepsAPositiveCountAndUsesEveryCoreForZeroOrLess) {
  EXPECT_EQ(resolve_threads(1), 1);
  EXPECT_EQ(resolve_threads(7), 7);
  const int cores = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  EXPECT_EQ(resolve_threads(0), cores);
  EXPECT_EQ(resolve_threads(-3), cores);
}

TEST(ThreadLimit, CapsWorkThatAsksForEveryCoreUntilItEndsAndNests) {
  const int cores = resolve_threads(0);
  const int opencv = cv::getNumThreads();
  {
    const ThreadLimit outer(3);
    EXPECT_EQ(resolve_threads(0), 3);
    EXPECT_EQ(resolve_threads(5), 5) << "an explicit count is the caller's choice";
    {
      const ThreadLimit inner(1);
      EXPECT_EQ(resolve_threads(0), 1);
      EXPECT_EQ(cv::getNumThreads(), 1);
      const ThreadLimit none(0);
      EXPECT_EQ(resolve_threads(0), 1) << "0 leaves the limit as it was";
    }
    EXPECT_EQ(resolve_threads(0), 3);
  }
  EXPECT_EQ(resolve_threads(0), cores);
  EXPECT_EQ(cv::getNumThreads(), opencv);
}

// Every worker waits until `threads` have started, so they are surely side by side.
int peak_of(int threads, int nested_threads) {
  reset_parallel_peak_threads();
  std::latch started(threads);
  parallel_for(threads, threads, [&](int) {
    started.arrive_and_wait();
    if (nested_threads > 0) parallel_for(nested_threads, nested_threads, [](int) {});
  });
  return parallel_peak_threads();
}

TEST(ParallelPeakThreads, CountsTheThreadsThatRanAtOnceWithTheCallerOnce) {
  EXPECT_EQ(peak_of(1, 0), 1);
  EXPECT_EQ(peak_of(3, 0), 3);
  reset_parallel_peak_threads();
  EXPECT_EQ(parallel_peak_threads(), 1) << "a reset forgets the threads that have ended";
}

// Waits until `n` threads have arrived, or two seconds: a rule that ran
// fewer threads side by side than expected shows as a smaller peak, not a hang.
void meet(std::atomic<int>& arrived, int n) {
  ++arrived;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  while (arrived.load() < n && std::chrono::steady_clock::now() < deadline) std::this_thread::yield();
}

TEST(ParallelPeakThreads, NestedWorkTakesOnlyTheFreeThreadsOfTheLimit) {
  {
    // Three workers that each want two: the limit of three is already running, so each inner call runs on
    // its worker's thread alone (without the rule, up to six threads).
    const ThreadLimit limit(3);
    EXPECT_EQ(peak_of(3, 2), 3);
  }
  {
    // Two workers under a limit of four: two threads are free, one for each inner call.
    const ThreadLimit limit(4);
    reset_parallel_peak_threads();
    std::atomic<int> outer{0}, inner{0};
    parallel_for(2, 2, [&](int) {
      meet(outer, 2);
      parallel_for(2, 2, [&](int) { meet(inner, 4); });
    });
    EXPECT_EQ(parallel_peak_threads(), 4);
  }
  {
    // A call nested in a call on one thread takes the threads free under the limit.
    const ThreadLimit limit(3);
    reset_parallel_peak_threads();
    std::atomic<int> inner{0};
    parallel_for(1, 1, [&](int) { parallel_for(3, 3, [&](int) { meet(inner, 3); }); });
    EXPECT_EQ(parallel_peak_threads(), 3);
  }
  // Every index still runs once, whatever was free.
  const ThreadLimit limit(2);
  std::vector<std::atomic<int>> calls(64);
  parallel_for(4, 2, [&](int outer) {
    parallel_chunks(16, 3, [&](std::size_t, std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) ++calls[static_cast<std::size_t>(outer) * 16 + i];
    });
  });
  for (std::size_t i = 0; i < calls.size(); ++i) EXPECT_EQ(calls[i].load(), 1) << i;
}

TEST(ParallelPeakThreads, AThreadWhoseWorkIsDoneJoinsANestedCallOfTheSameCommand) {
  // Two tasks on a limit of two: the second's inner call starts while both threads are busy, so it
  // starts on its own thread alone. The first task's thread, once free, must take its other index: as
  // the caller waiting for its call (task order 0) or as its helper. The inner indices wait for each
  // other, which the contract forbids; meet's time limit keeps a failure a failure, not a hang.
  const ThreadLimit limit(2);
  for (const bool first_on_caller : {true, false}) {
    SCOPED_TRACE(first_on_caller ? "the quick task on the caller's thread" : "the quick task on a helper");
    reset_parallel_peak_threads();
    std::atomic<bool> inner_started{false};
    std::atomic<int> arrived{0};
    std::mutex mutex;
    std::vector<std::thread::id> inner_threads;
    const std::function<void()> quick = [&] {
      while (!inner_started.load()) std::this_thread::yield();
    };
    const std::function<void()> nesting = [&] {
      parallel_for(2, 2, [&](int) {
        {
          const std::lock_guard lock(mutex);
          inner_threads.push_back(std::this_thread::get_id());
        }
        inner_started = true;
        meet(arrived, 2);
      });
    };
    parallel_invoke(first_on_caller ? std::vector{quick, nesting} : std::vector{nesting, quick}, 2);
    ASSERT_EQ(inner_threads.size(), 2u);
    EXPECT_NE(inner_threads[0], inner_threads[1]) << "the free thread did not join the inner call";
    EXPECT_EQ(parallel_peak_threads(), 2) << "joining adds no thread";
  }
}

TEST(ParallelPeakThreads, NoThreadTakesWorkOfAnotherCommandsCall) {
  // One command's caller waits for its slow task while another thread's command runs an inner call with
  // no thread free: the waiting caller must not take the inner call's index (its end would hold up the
  // first command's), so the inner indices run one after the other on their own thread.
  const ThreadLimit limit(2);
  std::atomic<bool> other_done{false};
  std::atomic<int> arrived{0};
  std::mutex mutex;
  std::vector<std::thread::id> inner_threads;
  std::thread::id other_thread;
  std::atomic<bool> waiting{false}, slow_started{false};
  const auto slow = [&] {
    slow_started = true;
    while (!other_done.load()) std::this_thread::yield();
  };
  // Ends once the helper has the slow task, leaving the caller waiting.
  const auto quick = [&] {
    while (!slow_started.load()) std::this_thread::yield();
    waiting = true;
  };
  std::thread other([&] {
    while (!waiting.load()) std::this_thread::yield();
    other_thread = std::this_thread::get_id();
    parallel_for(1, 1, [&](int) {
      parallel_for(2, 2, [&](int) {
        {
          const std::lock_guard lock(mutex);
          inner_threads.push_back(std::this_thread::get_id());
        }
        // Short: only how long the test takes when it passes.
        const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(200);
        ++arrived;
        while (arrived.load() < 2 && std::chrono::steady_clock::now() < deadline) std::this_thread::yield();
      });
    });
    other_done = true;
  });
  parallel_invoke({quick, slow}, 2);
  other.join();
  ASSERT_EQ(inner_threads.size(), 2u);
  EXPECT_EQ(inner_threads[0], other_thread);
  EXPECT_EQ(inner_threads[1], other_thread);
}

// (chunk, begin, end) of every call, sorted by chunk.
std::vector<std::tuple<std::size_t, std::size_t, std::size_t>> chunks_of(std::size_t count, int threads,
                                                                         std::size_t* used = nullptr) {
  std::mutex mutex;
  std::vector<std::tuple<std::size_t, std::size_t, std::size_t>> calls;
  const std::size_t n =
      parallel_chunks(count, threads, [&](std::size_t chunk, std::size_t begin, std::size_t end) {
        const std::lock_guard lock(mutex);
        calls.emplace_back(chunk, begin, end);
      });
  if (used) *used = n;
  std::sort(calls.begin(), calls.end());
  return calls;
}

TEST(ParallelChunks, SplitsTheRangeIntoContiguousInOrderChunks) {
  std::size_t used = 0;
  EXPECT_THAT(chunks_of(10, 3, &used),
              ElementsAre(std::tuple<std::size_t, std::size_t, std::size_t>{0, 0, 3},
                          std::tuple<std::size_t, std::size_t, std::size_t>{1, 3, 6},
                          std::tuple<std::size_t, std::size_t, std::size_t>{2, 6, 10}));
  EXPECT_EQ(used, 3u);
}

TEST(ParallelChunks, UsesNoMoreChunksThanIndices) {
  std::size_t used = 0;
  const auto calls = chunks_of(2, 8, &used);
  EXPECT_EQ(used, 2u);
  ASSERT_EQ(calls.size(), 2u);
  EXPECT_EQ(calls[0], (std::tuple<std::size_t, std::size_t, std::size_t>{0, 0, 1}));
  EXPECT_EQ(calls[1], (std::tuple<std::size_t, std::size_t, std::size_t>{1, 1, 2}));
}

TEST(ParallelChunks, RunsOneEmptyChunkForNoWork) {
  std::size_t used = 0;
  EXPECT_THAT(chunks_of(0, 4, &used),
              ElementsAre(std::tuple<std::size_t, std::size_t, std::size_t>{0, 0, 0}));
  EXPECT_EQ(used, 1u);
}

TEST(ParallelChunks, ZeroThreadsMeansEveryCore) {
  std::size_t used = 0;
  const std::size_t count = 1000;
  const auto calls = chunks_of(count, 0, &used);
  EXPECT_EQ(used, std::min<std::size_t>(count, static_cast<std::size_t>(resolve_threads(0))));
  EXPECT_EQ(calls.size(), used);
  EXPECT_EQ(std::get<2>(calls.back()), count);
}

TEST(ParallelChunks, RunsTheFirstChunkOnTheCallersThread) {
  std::thread::id first;
  std::vector<std::thread::id> ids(4);
  parallel_chunks(
      4, 4, [&](std::size_t chunk, std::size_t, std::size_t) { ids[chunk] = std::this_thread::get_id(); });
  EXPECT_EQ(ids[0], std::this_thread::get_id());
  for (std::size_t chunk = 1; chunk < ids.size(); ++chunk) EXPECT_NE(ids[chunk], std::this_thread::get_id());
}

TEST(ParallelChunks, PerChunkSumsMergeToTheSameTotalForAnyThreadCount) {
  std::vector<double> values(1001);
  for (std::size_t i = 0; i < values.size(); ++i) values[i] = 1.0 / static_cast<double>(i + 1);
  const auto total = [&](int threads) {
    std::vector<double> partial(static_cast<std::size_t>(resolve_threads(threads)), 0.0);
    parallel_chunks(values.size(), threads, [&](std::size_t chunk, std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) partial[chunk] += values[i];
    });
    double sum = 0;
    for (const double p : partial) sum += p;
    return sum;
  };
  // Same thread count, same chunks, same bits.
  EXPECT_EQ(total(3), total(3));
  EXPECT_NEAR(total(1), total(5), 1e-12);
}

TEST(ParallelChunks, FinishesEveryChunkThenRethrowsTheFirstFailureByChunkOrder) {
  std::atomic<int> finished{0};
  std::atomic<bool> chunk3_failing{false};
  try {
    parallel_chunks(4, 4, [&](std::size_t chunk, std::size_t, std::size_t) {
      if (chunk == 3) {
        chunk3_failing = true;
        throw std::logic_error("chunk 3");
      }
      if (chunk == 2) {
        // Chunk 3 fails first in time; chunk 2's failure still wins, by order.
        while (!chunk3_failing) std::this_thread::yield();
        throw std::runtime_error("chunk 2");
      }
      ++finished;
    });
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "chunk 2");
  }
  EXPECT_EQ(finished.load(), 2);
}

TEST(ParallelFor, CallsEveryIndexOnceForAnyThreadCount) {
  for (const int threads : {0, 1, 2, 3, 16}) {
    std::vector<std::atomic<int>> calls(257);
    parallel_for(257, threads, [&](int i) { ++calls[static_cast<std::size_t>(i)]; });
    for (std::size_t i = 0; i < calls.size(); ++i)
      EXPECT_EQ(calls[i].load(), 1) << "threads " << threads << " index " << i;
  }
}

TEST(ParallelFor, DoesNothingForAnEmptyRange) {
  int calls = 0;
  parallel_for(0, 4, [&](int) { ++calls; });
  parallel_for(-2, 4, [&](int) { ++calls; });
  EXPECT_EQ(calls, 0);
}

TEST(ParallelFor, PerIndexResultsDoNotDependOnTheThreadCount) {
  const auto run = [](int threads) {
    std::vector<double> rows(100);
    parallel_for(100, threads, [&](int r) {
      double v = 0;
      for (int k = 0; k <= r; ++k) v += 1.0 / (k + 1.0);
      rows[static_cast<std::size_t>(r)] = v;
    });
    return rows;
  };
  EXPECT_EQ(run(1), run(4));
  EXPECT_EQ(run(1), run(0));
}

TEST(ParallelFor, RethrowsAWorkersExceptionOnTheCaller) {
  EXPECT_THROW(parallel_for(50, 4,
                            [](int i) {
                              if (i == 17) throw std::runtime_error("index 17");
                            }),
               std::runtime_error);
}

TEST(ParallelFor, StartsNoFurtherIndexAfterAFailure) {
  std::vector<int> ran;
  try {
    parallel_for(10, 1, [&](int i) {
      ran.push_back(i);
      if (i == 3) throw std::runtime_error("index 3");
    });
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "index 3");
  }
  EXPECT_THAT(ran, ElementsAre(0, 1, 2, 3));
}

TEST(ParallelInvoke, RunsEveryTaskOnceEvenAfterAFailureAndRethrowsTheFirstByTaskOrder) {
  for (const int threads : {1, 2, 4}) {
    std::vector<std::atomic<int>> ran(6);
    std::vector<std::function<void()>> tasks;
    for (int t = 0; t < 6; ++t)
      tasks.emplace_back([&ran, t] {
        ++ran[static_cast<std::size_t>(t)];
        // The later task fails at once, the earlier one only after it: timing alone would name task 4.
        if (t == 4) throw std::runtime_error("task 4");
        if (t == 1) {
          std::this_thread::sleep_for(std::chrono::milliseconds(20));
          throw std::runtime_error("task 1");
        }
      });
    try {
      parallel_invoke(tasks, threads);
      FAIL() << "no exception";
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), "task 1") << threads << " threads";
    }
    for (const auto& count : ran) EXPECT_EQ(count.load(), 1) << threads << " threads";
  }
}

TEST(ParallelInvoke, DoesNothingWithoutTasks) { EXPECT_NO_THROW(parallel_invoke({}, 2)); }

}  // namespace
}  // namespace lightstage
