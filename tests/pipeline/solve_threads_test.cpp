// `solve --threads N` holds for every stage of a solve: decoding the frames,
// the solver, writing the maps and the report, whole, in bands, by tile and
// in a batch. parallel_peak_threads() sees the threads that ran at once.
#include "lightstage/common/parallel.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/pipeline/batch_solve.hpp"
#include "lightstage/pipeline/memory_budget.hpp"
#include "lightstage/pipeline/simulate_folder.hpp"
#include "lightstage/pipeline/solve_bands.hpp"
#include "lightstage/pipeline/solve_folder.hpp"
#include "lightstage/pipeline/solve_methods.hpp"
#include "lightstage/pipeline/solve_tiles.hpp"
#include "lightstage/testing/paths.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <limits>
#include <string>

namespace lightstage::pipeline {
namespace {

namespace fs = std::filesystem;

fs::path simulated(const fs::path& dir) {
  sim::SimulateOptions o;
  o.scene = "sphere";
  o.width = 40;
  o.height = 36;
  simulate_to_folder(lightstage::testing::source_dir() / "hw/rigs/sim-dome.yaml", o, dir);
  return dir;
}

SolveSettings settings_for(const std::string& method, int threads, const std::string& memory_limit = "auto") {
  SolveSettings s;
  s.method = method;
  s.threads = threads;
  s.memory_limit = memory_limit;
  s.resolve();
  return s;
}

class SolveThreads : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    stack_ = new fs::path(simulated(lightstage::testing::scratch_dir() / "stack"));
  }
  static void TearDownTestSuite() { delete stack_; }

  // The most threads that ran at once while `run` did.
  template <typename Run>
  static int peak_during(Run run) {
    reset_parallel_peak_threads();
    run();
    return parallel_peak_threads();
  }

  static fs::path* stack_;
  const fs::path out_ = lightstage::testing::scratch_dir();
};

fs::path* SolveThreads::stack_ = nullptr;

// With 1 and 2 threads the count can fail both ways: a stage that takes every
// core, or one nested into more (2 × 2), or work left on one thread.
TEST_F(SolveThreads, EveryStageOfAWholeSolveRunsOnTheThreadsAsked) {
  for (const int threads : {1, 2}) {
    for (const std::string method : {"l2", "robust", "biquadratic"}) {
      SCOPED_TRACE(fmt::format("{}, {} threads", method, threads));
      const fs::path out = out_ / fmt::format("{}-{}", method, threads);
      const int peak = peak_during([&] { solve_folder(*stack_, settings_for(method, threads), out); });
      ASSERT_TRUE(fs::exists(out / "report.html"));
      EXPECT_EQ(peak, threads);
    }
  }
}

TEST_F(SolveThreads, BandsTilesAndABatchRunOnTheThreadsAsked) {
  const io::StackOutline outline = io::read_stack_outline(*stack_);
  const BandPlan whole = plan_bands(outline, std::numeric_limits<std::size_t>::max(), coefficient_terms("l2"),
                                    solver_working_bytes(settings_for("l2", 1), outline.images));
  const std::string six_rows =
      std::to_string(whole.fixed_bytes + 6 * (whole.row_bytes + whole.read_ahead_row_bytes));
  const fs::path captures = out_ / "captures";
  fs::create_directories(captures);
  fs::create_directory_symlink(*stack_, captures / "a");
  for (const int threads : {1, 2}) {
    SCOPED_TRACE(fmt::format("{} threads", threads));
    const fs::path out = out_ / std::to_string(threads);
    SolveReport banded;
    const int in_bands = peak_during(
        [&] { banded = solve_folder(*stack_, settings_for("l2", threads, six_rows), out / "bands"); });
    ASSERT_TRUE(banded.summary.contains("bands"));
    EXPECT_EQ(in_bands, threads);

    const SolveSettings robust = settings_for("robust", threads);
    const int by_tile = peak_during([&] {
      for (const char* tile : {"prepare", "0/2", "1/2", "merge"})
        solve_tile(*stack_, robust, out / "tiled", {}, tile);
    });
    ASSERT_TRUE(fs::exists(out / "tiled" / "normal.png"));
    EXPECT_EQ(by_tile, threads);

    const int in_batch =
        peak_during([&] { solve_batch(captures, settings_for("l2", threads), out / "batch", {}); });
    ASSERT_TRUE(fs::exists(out / "batch" / "a" / "normal.png"));
    EXPECT_EQ(in_batch, threads);
  }
}

}  // namespace
}  // namespace lightstage::pipeline
