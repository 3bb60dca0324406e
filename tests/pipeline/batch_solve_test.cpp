// `batch` (batch_solve.hpp): which folders are captures, what counts as done,
// and what it refuses before solving anything.
#include "lightstage/pipeline/batch_solve.hpp"

#include "lightstage/pipeline/simulate_folder.hpp"
#include "lightstage/testing/errors.hpp"
#include "lightstage/testing/paths.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>

namespace lightstage::pipeline {
namespace {

namespace fs = std::filesystem;
using lightstage::testing::error_of;
using ::testing::HasSubstr;

void simulated(const fs::path& dir) {
  sim::SimulateOptions o;
  o.scene = "sphere";
  o.width = 24;
  o.height = 20;
  simulate_to_folder(lightstage::testing::source_dir() / "hw/rigs/sim-dome.yaml", o, dir);
}

SolveSettings settings_for(const std::string& method) {
  SolveSettings s;
  s.method = method;
  s.threads = 2;
  s.resolve();
  return s;
}

TEST(BatchSolve, CapturesAreStackFoldersOrTheirStackSubfolderByName) {
  const fs::path dir = lightstage::testing::scratch_dir();
  simulated(dir / "in" / "z");
  simulated(dir / "in" / "m" / "stack");
  fs::create_directories(dir / "in" / "empty");
  std::ofstream(dir / "in" / "notes.txt") << "not a capture";
  const std::vector<BatchCapture> captures = find_batch_captures(dir / "in");
  ASSERT_EQ(captures.size(), 2u);
  EXPECT_EQ(captures[0].name, "m");
  EXPECT_EQ(captures[0].stack, dir / "in" / "m" / "stack");
  EXPECT_EQ(captures[1].name, "z");

  EXPECT_THAT(error_of([&] { find_batch_captures(dir / "in" / "empty"); }), HasSubstr("no capture in it"));
  EXPECT_THAT(error_of([&] { find_batch_captures(dir / "nowhere"); }), HasSubstr("not a folder of captures"));
  EXPECT_THAT(error_of([&] { solve_batch(dir / "in", settings_for("l2"), dir / "in" / "out", {}); }),
              HasSubstr((dir / "in").string()));
}

TEST(BatchSolve, AResultOfAnotherMethodIsNotDone) {
  const fs::path dir = lightstage::testing::scratch_dir();
  simulated(dir / "in" / "a");
  BatchReport report = solve_batch(dir / "in", settings_for("l2"), dir / "out", {});
  EXPECT_EQ(report.solved, 1u);
  report = solve_batch(dir / "in", settings_for("l2"), dir / "out", {});
  EXPECT_EQ(report.done_before, 1u);
  EXPECT_EQ(report.captures[0].summary["method"], "l2");
  report = solve_batch(dir / "in", settings_for("robust"), dir / "out", {});
  EXPECT_EQ(report.solved, 1u);
  EXPECT_EQ(report.captures[0].summary["method"], "robust");
}

}  // namespace
}  // namespace lightstage::pipeline
