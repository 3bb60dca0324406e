// The dome demo in process: this test is the host, lightstage-sim and
// lightstage-domed run as its children (from the build's bin/).
#include "lightstage/pipeline/dome_demo.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/io/solve_output.hpp"
#include "lightstage/testing/paths.hpp"

#include <gtest/gtest.h>

namespace lightstage::pipeline {
namespace {

namespace fs = std::filesystem;

TEST(DomeDemo, RunsEveryStageWithTheChosenMethod) {
  const fs::path dir = testing::scratch_dir();
  DomeDemoOptions options;
  options.rig = testing::source_dir() / "hw/rigs/sim-dome.yaml";
  options.out = dir / "demo";
  options.programs = testing::bin_dir();
  options.scene = "sphere";
  options.width = options.height = 96;
  options.mode = OutputMode::kQuiet;
  options.solve.method = "robust";
  const nlohmann::json summary = run_dome_demo(options);
  for (const char* stage : {"chrome-1", "chrome-2", "object"})
    EXPECT_EQ(summary["captures"][stage]["frames"].get<int>(), 96) << stage;
  EXPECT_EQ(summary["calibration"]["measured"].get<int>(), 96);
  EXPECT_LT(summary["solve"]["error_vs_ground_truth"]["mean_deg"].get<double>(), 3.0) << summary.dump();
  EXPECT_EQ(io::read_solve_folder(options.out / "result").method(), "robust");
  EXPECT_TRUE(fs::exists(options.out / "surface" / "mesh.ply"));
  EXPECT_TRUE(fs::exists(options.out / "demo.json"));
}

TEST(DomeDemo, DefaultsToLeastSquaresWithoutShadows) {
  const SolveSettings settings = default_demo_solve();
  EXPECT_EQ(settings.method, "l2");
  ASSERT_TRUE(settings.shadow_threshold.has_value());
  EXPECT_EQ(*settings.shadow_threshold, 0.02);
}

TEST(DomeDemo, ABadMethodFailsBeforeAnyProgramStarts) {
  const fs::path dir = testing::scratch_dir();
  DomeDemoOptions options;
  options.rig = testing::source_dir() / "hw/rigs/sim-dome.yaml";
  options.out = dir / "demo";
  options.programs = dir / "nowhere";  // would fail later, naming the programs
  options.mode = OutputMode::kQuiet;
  options.solve.method = "lambertian";
  try {
    run_dome_demo(options);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--method"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace lightstage::pipeline
