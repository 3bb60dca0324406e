// The folder-to-folder steps in process: simulate a stack, solve it, read the
// solve folder back, integrate a surface from it and relight it.
#include "lightstage/common/error.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/normal_map.hpp"
#include "lightstage/host/io/solve_output.hpp"
#include "lightstage/pipeline/integrate_folder.hpp"
#include "lightstage/pipeline/relight_folder.hpp"
#include "lightstage/pipeline/simulate_folder.hpp"
#include "lightstage/pipeline/solve_folder.hpp"
#include "lightstage/pipeline/solve_methods.hpp"
#include "lightstage/testing/paths.hpp"

#include <gtest/gtest.h>

#include <fstream>

namespace lightstage::pipeline {
namespace {

namespace fs = std::filesystem;

fs::path simulated_sphere(const fs::path& dir) {
  sim::SimulateOptions options;
  options.scene = "sphere";
  options.light_model = sim::LightModel::kDistant;
  options.width = options.height = 64;
  options.threads = 2;
  const fs::path stack = dir / "stack";
  const nlohmann::json written =
      simulate_to_folder(testing::source_dir() / "hw/rigs/sim-dome.yaml", options, stack);
  EXPECT_EQ(written["frames"], 96);
  EXPECT_EQ(written["width"], 64);
  return stack;
}

// The simulated sphere solved by `method` into dir/result.
SolveReport solved_sphere(const fs::path& dir, const std::string& method) {
  SolveSettings settings;
  settings.method = method;
  settings.shadow_threshold = 0.02;
  settings.resolve();
  return solve_folder(simulated_sphere(dir), settings, dir / "result");
}

TEST(PipelineFolders, SolvesASimulatedStackAndMeasuresItsError) {
  const fs::path dir = testing::scratch_dir();
  const SolveReport report = solved_sphere(dir, "l2");
  ASSERT_TRUE(report.error.has_value());
  EXPECT_LT(report.error->mean, 1.0);
  EXPECT_GT(report.error->count, 1000u);
  EXPECT_EQ(report.summary["method"], "l2");
  EXPECT_TRUE(fs::exists(dir / "result" / "report.html"));

  const io::SolveFolder folder = io::read_solve_folder(dir / "result");
  EXPECT_EQ(folder.summary, report.summary);
  EXPECT_EQ(static_cast<std::size_t>(cv::countNonZero(folder.solved)), report.error->count);
}

TEST(PipelineFolders, AnyRegisteredMethodSolvesAFolder) {
  const fs::path dir = testing::scratch_dir();
  const SolveReport report = solved_sphere(dir, "biquadratic");
  EXPECT_EQ(report.summary["method"], "biquadratic");
  ASSERT_TRUE(report.error.has_value());
  EXPECT_LT(report.error->mean, 2.0);
  const io::SolveFolder folder = io::read_solve_folder(dir / "result");
  EXPECT_EQ(folder.reflectance_order, 2);
  EXPECT_EQ(folder.coefficients.channels(), static_cast<int>(report.summary["files"]["brdf"].size()));
}

TEST(PipelineFolders, IntegratesAndRelightsASolveFolder) {
  const fs::path dir = testing::scratch_dir();
  solved_sphere(dir, "l2");

  IntegrateSettings integrate;
  integrate.input = (dir / "result").string();
  integrate.out = (dir / "surface").string();
  double last = -1;
  bool monotone = true;
  const IntegrateReport surface = integrate_folder(integrate, [&](double fraction) {
    monotone = monotone && fraction >= last;
    last = fraction;
  });
  EXPECT_TRUE(monotone);
  EXPECT_DOUBLE_EQ(last, 1.0);
  EXPECT_GT(surface.stats.pixels, 1000u);
  EXPECT_TRUE(fs::exists(dir / "surface" / "depth.pfm"));
  EXPECT_TRUE(fs::exists(dir / "surface" / "mesh.ply"));

  RelightSettings relight;
  relight.input = dir / "result";
  relight.out = dir / "relit";
  relight.lights = {Vec3(0, 0, 1), Vec3(1, 0, 1)};
  const nlohmann::json relit = relight_folder(relight);
  ASSERT_EQ(relit["frames"].size(), 2u);
  EXPECT_EQ(relit["model"], "lambert");
  const cv::Mat frontal = io::read_image(dir / "relit" / "relit_000.png");
  const cv::Mat side = io::read_image(dir / "relit" / "relit_001.png");
  ASSERT_EQ(frontal.type(), CV_16UC1);
  // Lit from the right (+x, image columns grow to the right), the right half is brighter.
  const int w = side.cols;
  EXPECT_GT(cv::mean(side.colRange(w / 2, w))[0], 2 * cv::mean(side.colRange(0, w / 2))[0]);
  EXPECT_GT(cv::mean(frontal)[0], 0);
  relight.lights.clear();
  EXPECT_THROW(relight_folder(relight), InputError);
}

TEST(PipelineFolders, IntegrateNeedsNormals) {
  IntegrateSettings integrate;
  integrate.out = (testing::scratch_dir() / "surface").string();
  EXPECT_THROW(integrate_folder(integrate), InputError);
  integrate.input = (testing::scratch_dir() / "missing").string();
  EXPECT_THROW(integrate_folder(integrate), InputError);
}

}  // namespace
}  // namespace lightstage::pipeline
