// One capture solved as independent tile jobs and merged (solve_tiles.hpp)
// equals the single run: the same maps float for float, counts, facts,
// threshold and error; and the jobs and the merge refuse what would mix runs.
#include "lightstage/pipeline/solve_tiles.hpp"

#include "lightstage/host/io/exr.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/pipeline/simulate_folder.hpp"
#include "lightstage/pipeline/solve_bands.hpp"
#include "lightstage/pipeline/solve_folder.hpp"
#include "lightstage/testing/errors.hpp"
#include "lightstage/testing/light_statistics.hpp"
#include "lightstage/testing/paths.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <limits>

namespace lightstage::pipeline {
namespace {

namespace fs = std::filesystem;
using lightstage::testing::error_of;
using ::testing::HasSubstr;

fs::path simulated(const fs::path& dir) {
  sim::SimulateOptions o;
  o.scene = "bumps";
  o.width = 40;
  o.height = 37;  // rows that do not split evenly into the tiles
  simulate_to_folder(lightstage::testing::source_dir() / "hw/rigs/sim-dome.yaml", o, dir);
  return dir;
}

SolveSettings settings_for(const std::string& method, const fs::path& stack, int band_rows) {
  SolveSettings s;
  s.method = method;
  s.threads = 2;
  const BandPlan whole = plan_bands(io::read_stack_outline(stack), std::numeric_limits<std::size_t>::max());
  s.memory_limit = std::to_string(whole.fixed_bytes + static_cast<std::size_t>(band_rows) *
                                                          (whole.row_bytes + whole.read_ahead_row_bytes));
  s.resolve();
  return s;
}

void expect_same_map(const cv::Mat& a, const cv::Mat& b, const std::string& what) {
  ASSERT_EQ(a.type(), b.type()) << what;
  ASSERT_EQ(a.size(), b.size()) << what;
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0) << what;
}

void expect_same_solve(const SolveReport& single, const SolveReport& merged, const fs::path& a,
                       const fs::path& b) {
  for (const char* key : {"pixels_in_mask", "pixels_solved", "pixels_rejected_too_few_observations",
                          "pixels_rejected_degenerate", "lights", "radiometry", "facts"})
    EXPECT_EQ(merged.summary[key], single.summary[key]) << key;
  EXPECT_EQ(merged.summary["parameters"]["shadow_threshold_choice"],
            single.summary["parameters"]["shadow_threshold_choice"]);
  ASSERT_TRUE(single.error && merged.error);
  EXPECT_EQ(merged.error->mean, single.error->mean);
  EXPECT_EQ(merged.error->median, single.error->median);
  EXPECT_EQ(merged.error->count, single.error->count);
  expect_same_map(io::read_exr(b / "normal.exr", {"R", "G", "B"}),
                  io::read_exr(a / "normal.exr", {"R", "G", "B"}), "normals");
  for (const char* file : {"albedo.pfm", "residual.pfm", "confidence.pfm"})
    expect_same_map(io::read_pfm(b / file), io::read_pfm(a / file), file);
  lightstage::testing::expect_same_light_statistics(single.summary, merged.summary);
  // The report shows them without decoding the stack again.
  EXPECT_NE(lightstage::testing::read_text(b / "report.html").find("<section id=\"light-statistics\">"),
            std::string::npos);
  EXPECT_TRUE(fs::exists(b / "report.html"));
  EXPECT_FALSE(fs::exists(b / "tiles"));  // the parts go once merged
}

TEST(SolveTiles, TileJobsInAnyOrderMergeIntoTheSingleRun) {
  const fs::path dir = lightstage::testing::scratch_dir();
  const fs::path stack = simulated(dir / "stack");
  for (const char* method : {"robust", "l2", "sbl"}) {
    SCOPED_TRACE(method);
    const SolveSettings settings = settings_for(method, stack, 5);
    const fs::path single = dir / (std::string(method) + "_single"),
                   tiled = dir / (std::string(method) + "_tiles");
    const SolveReport whole = solve_folder(stack, settings, single);
    ASSERT_TRUE(whole.summary.contains("bands"));
    EXPECT_EQ(solve_tile(stack, settings, tiled, {}, "prepare").summary["tile"], "prepare");
    // Each job on its own machine, with its own memory: bands of other heights give the same result.
    for (const auto& [tile, rows] : {std::pair{"2/3", 4}, {"0/3", 7}, {"1/3", 50}}) {
      const SolveReport part = solve_tile(stack, settings_for(method, stack, rows), tiled, {}, tile);
      EXPECT_TRUE(fs::exists(part.summary["part"].get<std::string>())) << tile;
    }
    // A job run again (a preempted array task) replaces its own part.
    solve_tile(stack, settings, tiled, {}, "1/3");
    const SolveReport merged = solve_tile(stack, settings, tiled, {}, "merge");
    EXPECT_EQ(merged.summary["bands"]["tiles"], 3);
    expect_same_solve(whole, merged, single, tiled);
  }
}

TEST(SolveTiles, JobsWithoutAPlanEstimateTheSameThresholdAndShareIt) {
  const fs::path dir = lightstage::testing::scratch_dir();
  const fs::path stack = simulated(dir / "stack");
  SolveSettings settings = settings_for("monotonic", stack, 6);
  settings.crop = "3,2,30,31";  // the tiles split the region's rows
  const SolveReport whole = solve_folder(stack, settings, dir / "single");
  solve_tile(stack, settings, dir / "tiles", {}, "1/2");
  EXPECT_TRUE(fs::exists(dir / "tiles" / "tiles" / "plan.json"));  // written by the first job
  solve_tile(stack, settings, dir / "tiles", {}, "0/2");
  expect_same_solve(whole, solve_tile(stack, settings, dir / "tiles", {}, "merge"), dir / "single",
                    dir / "tiles");
}

TEST(SolveTiles, WhatWouldMixRunsIsRefusedByName) {
  const fs::path dir = lightstage::testing::scratch_dir();
  const fs::path stack = simulated(dir / "stack");
  const SolveSettings robust = settings_for("robust", stack, 5);
  const fs::path out = dir / "out";
  for (const char* bad : {"3/3", "a/b", "0/0", "-1/2", "1", "1/2/3", "prep"})
    EXPECT_THAT(error_of([&] { solve_tile(stack, robust, out, {}, bad); }), HasSubstr("--tile")) << bad;
  EXPECT_THAT(error_of([&] { solve_tile(stack, robust, out, {}, "0/38"); }),
              HasSubstr("more tiles than the image has rows (37)"));
  EXPECT_THAT(error_of([&] { solve_tile(stack, settings_for("biquadratic", stack, 5), out, {}, "0/2"); }),
              HasSubstr("--method biquadratic needs the whole image"));
  // Its fall-off is estimated over the whole object, which no tile job sees.
  SolveSettings azimuth = settings_for("monotonic", stack, 5);
  azimuth.azimuth_from = "bilinear";
  EXPECT_THAT(error_of([&] { solve_tile(stack, azimuth, out, {}, "0/2"); }),
              HasSubstr("--method monotonic needs the whole image"));
  EXPECT_THAT(error_of([&] { solve_tile(stack, robust, out, {}, "merge"); }),
              HasSubstr("no tile parts to merge"));

  solve_tile(stack, robust, out, {}, "0/3");
  solve_tile(stack, robust, out, {}, "2/3");
  EXPECT_THAT(error_of([&] { solve_tile(stack, robust, out, {}, "merge"); }),
              HasSubstr("tile(s) 1 of 3 missing: run --tile I/3 for each"));
  solve_tile(stack, robust, out, {}, "1/3");
  EXPECT_THAT(error_of([&] { solve_tile(stack, settings_for("l1", stack, 5), out, {}, "merge"); }),
              HasSubstr("solved by another run (method \"robust\" there, \"l1\" here)"));
  EXPECT_FALSE(fs::exists(out / "summary.json"));
  // A damaged part is named, and how to mend it.
  std::ofstream(out / "tiles" / "part-0-of-3" / "part.json")
      << R"({"format": "lightstage solve tile part 2"})";
  EXPECT_THAT(error_of([&] { solve_tile(stack, robust, out, {}, "merge"); }),
              HasSubstr("part-0-of-3/part.json: [json.exception"));
  std::ofstream(out / "tiles" / "part-0-of-3" / "part.json") << "{not json";
  EXPECT_THAT(error_of([&] { solve_tile(stack, robust, out, {}, "merge"); }),
              HasSubstr("part-0-of-3/part.json: not a 'lightstage solve tile part 2' file"));

  // A plan made for another capture is not used for this one.
  const fs::path other = simulated(dir / "other");
  EXPECT_THAT(error_of([&] { solve_tile(other, robust, out, {}, "1/3"); }),
              HasSubstr("plan.json: made for another run (input"));
}

}  // namespace
}  // namespace lightstage::pipeline
