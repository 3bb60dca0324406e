// The first slice end to end through the CLI: simulate a stack on the default
// dome, solve it, evaluate it — and check the numbers against ground truth.
#include "lightstage/host/io/normal_map.hpp"
#include "lightstage/testing/paths.hpp"
#include "lightstage/testing/run.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>

namespace lightstage {
namespace {

using testing::run_lightstage;

nlohmann::json read_json(const std::filesystem::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

TEST(Pipeline, LambertianSphereUnderDistantLightsSolvesToUnderHalfADegree) {
  const auto dir = testing::scratch_dir();
  const auto stack = dir / "stack";
  const auto result = dir / "result";
  auto run = run_lightstage({"simulate", "--scene", "sphere", "--lights", "distant", "--width", "160",
                             "--height", "160", "--out", stack.string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  for (const char* file :
       {"filenames.txt", "001.png", "096.png", "light_directions.txt", "light_intensities.txt", "mask.png",
        "Normal_gt.png", "depth_gt.pfm", "manifest.json"}) {
    EXPECT_TRUE(std::filesystem::exists(stack / file)) << file;
  }
  const auto manifest = read_json(stack / "manifest.json");
  EXPECT_EQ(manifest["frames"].size(), 96u);

  run = run_lightstage({"solve", "--input", stack.string(), "--method", "l2", "--shadow-threshold", "0.02",
                        "--out", result.string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  for (const char* file : {"normal.png", "normal_vis.png", "albedo.png", "summary.json"}) {
    EXPECT_TRUE(std::filesystem::exists(result / file)) << file;
  }
  const auto summary = read_json(result / "summary.json");
  EXPECT_EQ(summary["method"], "l2");
  EXPECT_EQ(summary["pixels_solved"], summary["pixels_in_mask"]);
  EXPECT_GT(summary["pixels_solved"].get<int>(), 10000);

  run =
      run_lightstage({"eval", "--pred", (result / "normal.png").string(), "--gt", stack.string(), "--json"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto stats = nlohmann::json::parse(run.out);
  EXPECT_LT(stats["mean_deg"].get<double>(), 0.5) << run.out;
  EXPECT_GT(stats["count"].get<int>(), 10000);
  EXPECT_EQ(stats["missing"].get<int>(), 0);
  // solve's own measurement agrees with eval's.
  EXPECT_NEAR(summary["error_vs_ground_truth"]["mean_deg"].get<double>(), stats["mean_deg"].get<double>(),
              1e-3);
}

TEST(Pipeline, SolverSeesNearLightsAsAnError) {
  // The same sphere under near LEDs: the distant-light solver must be visibly
  // worse (this is what LED-position calibration exists to fix). Guards against
  // a simulator that silently ignores --lights.
  const auto dir = testing::scratch_dir();
  auto run = run_lightstage({"simulate", "--scene", "sphere", "--lights", "near", "--width", "128",
                             "--height", "128", "--out", (dir / "stack").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  run = run_lightstage({"solve", "--input", (dir / "stack").string(), "--method", "l2", "--shadow-threshold",
                        "0.02", "--out", (dir / "result").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto summary = read_json(dir / "result" / "summary.json");
  EXPECT_GT(summary["error_vs_ground_truth"]["mean_deg"].get<double>(), 1.0);
}

}  // namespace
}  // namespace lightstage
