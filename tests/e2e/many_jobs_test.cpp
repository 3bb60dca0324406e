// Issue 18: one capture as several processes (`solve --tile`, run at once as
// GNU parallel or a job array would, without a prepared plan) merged into the
// single run's result, and `batch` over a folder of captures, carrying on
// where it stopped.
#include "lightstage/host/io/exr.hpp"
#include "lightstage/testing/paths.hpp"
#include "lightstage/testing/run.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <future>

namespace lightstage {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

nlohmann::json read_json(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

void simulate(const fs::path& stack, const std::string& scene) {
  const auto r = testing::run_lightstage(
      {"simulate", "--quiet", "--rig", (testing::source_dir() / "hw/rigs/sim-dome.yaml").string(), "--scene",
       scene, "--width", "48", "--height", "40", "--out", stack.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
}

TEST(ManyJobs, TileJobsRunAtOnceMergeIntoTheSingleRun) {
  const fs::path dir = testing::scratch_dir();
  const fs::path stack = dir / "stack", out = dir / "tiles";
  simulate(stack, "bumps");
  const std::vector<std::string> flags = {"--input", stack.string(), "--method",
                                          "robust",  "--out",        out.string()};
  const auto with = [&](std::vector<std::string> args) {
    args.insert(args.begin(), "solve");
    args.insert(args.end(), flags.begin(), flags.end());
    return args;
  };
  std::vector<std::future<testing::RunResult>> jobs;
  for (const char* tile : {"0/3", "1/3", "2/3"})
    jobs.push_back(std::async(std::launch::async, [&, tile] {
      return testing::run_lightstage(with({"--tile", tile}));
    }));
  for (auto& job : jobs) {
    const auto r = job.get();
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_THAT(r.out, HasSubstr("robust: tile "));
  }
  const auto merged = testing::run_lightstage(with({"--tile", "merge"}));
  ASSERT_EQ(merged.exit_code, 0) << merged.err;
  EXPECT_THAT(merged.out, HasSubstr("mean"));  // the error against ground truth, as a single run prints it

  auto single = flags;
  single.back() = (dir / "single").string();
  single.insert(single.begin(), "solve");
  const auto r = testing::run_lightstage(single);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(cv::norm(io::read_exr(out / "normal.exr", {"R", "G", "B"}),
                     io::read_exr(dir / "single" / "normal.exr", {"R", "G", "B"}), cv::NORM_INF),
            0);
  EXPECT_EQ(read_json(out / "summary.json")["error_vs_ground_truth"],
            read_json(dir / "single" / "summary.json")["error_vs_ground_truth"]);

  const auto missing = testing::run_lightstage(with({"--tile", "merge"}));
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_THAT(missing.err, HasSubstr("no tile parts to merge"));
}

TEST(ManyJobs, BatchReportsFailuresGoesOnAndResumes) {
  const fs::path dir = testing::scratch_dir();
  const fs::path captures = dir / "captures", results = dir / "results";
  simulate(captures / "a", "sphere");
  simulate(captures / "b" / "stack", "bumps");  // as `capture` and `demo` lay it out
  simulate(captures / "c", "sphere");
  fs::remove(captures / "c" / "mask.png");
  std::ofstream(captures / "c" / "mask.png") << "not a PNG";
  fs::create_directories(captures / "notes");  // not a capture: ignored

  const std::vector<std::string> args = {"batch", "--input", captures.string(), "--method",
                                         "l2",    "--out",   results.string()};
  auto r = testing::run_lightstage(args);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("1 of 3 captures failed"));
  EXPECT_THAT(r.out, HasSubstr("[3/3] c: failed: "));
  EXPECT_THAT(r.out, HasSubstr("mask.png"));
  nlohmann::json batch = read_json(results / "batch.json");
  EXPECT_EQ(batch["solved"], 2);
  EXPECT_EQ(batch["failed"], 1);
  EXPECT_TRUE(fs::exists(results / "b" / "normal.png"));

  // Mended, and a finished result made incomplete (the run was interrupted before its report).
  simulate(dir / "good", "sphere");
  fs::remove_all(captures / "c");
  fs::rename(dir / "good", captures / "c");
  fs::remove(results / "b" / "report.html");
  r = testing::run_lightstage(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("[1/3] a: done before"));
  EXPECT_THAT(r.out, HasSubstr("[2/3] b: solved"));
  EXPECT_THAT(r.out, HasSubstr("[3/3] c: solved (mean error "));
  batch = read_json(results / "batch.json");
  EXPECT_EQ(batch["done_before"], 1);
  EXPECT_EQ(batch["solved"], 2);
  EXPECT_GT(batch["captures"][0]["error_vs_ground_truth"]["mean_deg"].get<double>(), 0);

  const auto inside = testing::run_lightstage(
      {"batch", "--input", captures.string(), "--out", (captures / "results").string()});
  EXPECT_EQ(inside.exit_code, 1);
  EXPECT_THAT(inside.err, HasSubstr(captures.string()));
}

}  // namespace
}  // namespace lightstage
