// The shadow threshold estimated from the data (shadow_threshold.hpp) on
// simulated stacks of known noise: a camera with a black level, one with
// dark frames, one with neither (its shadows clipped at zero), noise-free
// data and the material sweep's observations; and that `solve` with no flag
// is at least as accurate as with the old fixed 1e-6.
#include "lightstage/host/shadow_threshold.hpp"

#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/pipeline/material_sweep.hpp"
#include "lightstage/pipeline/simulate_folder.hpp"
#include "lightstage/pipeline/solve_folder.hpp"
#include "lightstage/pipeline/solve_methods.hpp"
#include "lightstage/pipeline/synthetic_observations.hpp"
#include "lightstage/sim/material.hpp"
#include "lightstage/testing/paths.hpp"
#include "lightstage/testing/sanitizers.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

namespace lightstage::pipeline {
namespace {

namespace fs = std::filesystem;

constexpr double kReadNoiseE = 20, kFullWellE = 20000;

fs::path simulated(const fs::path& dir, sim::NoiseModel noise, double black_level,
                   const std::string& scene = "shiny-sphere") {
  sim::SimulateOptions options;
  options.scene = scene;
  options.light_model = sim::LightModel::kDistant;
  options.width = options.height = 96;
  options.threads = 2;
  options.sensor.noise = noise;
  options.sensor.read_noise_e = kReadNoiseE;
  options.sensor.full_well_e = kFullWellE;
  options.sensor.black_level = black_level;
  simulate_to_folder(testing::source_dir() / "hw/rigs/sim-dome.yaml", options, dir);
  return dir;
}

// The read noise in values at unit light (radiometry.hpp) of the stack's first frame.
double read_noise_value(const ImageStack& stack) {
  return kReadNoiseE / kFullWellE / stack.frames.front().light_intensity.x();
}

ShadowThreshold estimated(const fs::path& dir) {
  const SolveInput input = load_solve_input(dir, {});
  return input.shadow;
}

TEST(ShadowThreshold, ABlackLevelCameraGetsThreeSigmaOfItsReadNoise) {
  const fs::path dir = simulated(testing::scratch_dir() / "black", sim::NoiseModel::kPhysical, 2048);
  const ImageStack stack = io::load_stack(dir);
  const ShadowThreshold t = estimated(dir);
  const double sigma = read_noise_value(stack);
  RecordProperty("threshold", fmt::format("{:.5f} (read noise {:.5f})", t.value, sigma));
  EXPECT_EQ(t.source, "black level");
  EXPECT_NEAR(t.noise, sigma, 0.25 * sigma);
  EXPECT_NEAR(t.level, 0, sigma);
  EXPECT_NEAR(t.value, 3 * sigma, sigma);
  EXPECT_GT(t.background_samples, 1000u);
}

TEST(ShadowThreshold, DarkFramesAreNamedAndGiveTheSameNoise) {
  const fs::path dir = simulated(testing::scratch_dir() / "black", sim::NoiseModel::kPhysical, 2048);
  ImageStack stack = io::load_stack(dir);
  // The averaged dark of a black-level camera is its black level, pixel by pixel.
  const cv::Mat dark(stack.frames.front().image.size(), CV_32FC1, cv::Scalar::all(2048));
  for (Frame& frame : stack.frames) {
    frame.dark = dark;
    frame.dark_file = "dark.pfm";
    frame.black_level = 0;
  }
  const ShadowThreshold t = estimate_shadow_threshold(stack, make_observations(stack));
  const double sigma = read_noise_value(stack);
  EXPECT_EQ(t.source, "dark frames");
  EXPECT_NEAR(t.value, 3 * sigma, sigma);
}

TEST(ShadowThreshold, WithoutABlackLevelTheClippedNoiseFloorStillShows) {
  // Black level 0: the sensor clips the negative half of the noise at zero.
  const fs::path dir = simulated(testing::scratch_dir() / "clipped", sim::NoiseModel::kPhysical, 0);
  const ImageStack stack = io::load_stack(dir);
  const ShadowThreshold t = estimated(dir);
  const double sigma = read_noise_value(stack);
  RecordProperty("threshold", fmt::format("{:.5f} (read noise {:.5f})", t.value, sigma));
  EXPECT_EQ(t.source, "noise floor");
  EXPECT_GT(t.value, 2 * sigma);
  EXPECT_LT(t.value, 5 * sigma);
}

TEST(ShadowThreshold, WithoutABackgroundTheClippedZerosAndTheirPartnersGiveTheNoise) {
  // The bunny on its floor fills the frame: no background, and every pixel's
  // darkest value is a clipped zero. The small values beside the zeros are the noise.
  const fs::path dir =
      simulated(testing::scratch_dir() / "filled", sim::NoiseModel::kPhysical, 0, "bunny-shadows");
  const ImageStack stack = io::load_stack(dir);
  const ShadowThreshold t = estimated(dir);
  const double sigma = read_noise_value(stack);
  RecordProperty("threshold", fmt::format("{:.5f} (read noise {:.5f})", t.value, sigma));
  EXPECT_EQ(t.background_samples, 0u);
  EXPECT_EQ(t.level, 0);
  EXPECT_NEAR(t.noise, sigma, 0.3 * sigma);
  EXPECT_GT(t.value, 2 * sigma);
  EXPECT_LT(t.value, 5 * sigma);
}

TEST(ShadowThreshold, NoiseFreeDataAndTheSweepKeepTheSyntheticDefault) {
  const fs::path dir = simulated(testing::scratch_dir() / "exact", sim::NoiseModel::kNone, 0);
  EXPECT_EQ(estimated(dir).value, kMinShadowThreshold);
  // Nor does a noise-free object that fills the frame: its zeros have no noise beside them.
  EXPECT_EQ(estimated(simulated(testing::scratch_dir() / "exact-filled", sim::NoiseModel::kNone, 0,
                                "bunny-shadows"))
                .value,
            kMinShadowThreshold);
  // The sweep's observations: exact zeros in shadow whatever λ (its noise is y + λ·y·X).
  for (const auto& material : default_sweep_materials()) {
    for (const double lambda : {-1.0, 0.05, 0.15}) {
      SyntheticOptions options;
      options.noise = lambda;
      for (const double min_z : {0.05, std::cos(rad_from_deg(43))}) {
        const SyntheticScene scene =
            render_synthetic(sim::parse_material(material), sweep_grid_size(), sweep_grid_normal,
                             random_hemisphere_lights(100, min_z, 1), options);
        EXPECT_EQ(estimate_shadow_threshold(scene.observations).value, kMinShadowThreshold)
            << material << " lambda " << lambda << " min_z " << min_z;
      }
    }
  }
}

// With no flag, `solve` on noisy simulated captures is at least as accurate
// as with the fixed 1e-6 that read the noise floor as lit.
TEST(ShadowThreshold, TheEstimateIsNoWorseThanTheOldDefaultOnNoisyCaptures) {
  LIGHTSTAGE_MEASURED_IN_RELEASE_ONLY(
      "ShadowThreshold.WithoutABackgroundTheClippedZerosAndTheirPartnersGiveTheNoise");
  const fs::path root = testing::scratch_dir();
  for (const double black_level : {0.0, 2048.0}) {
    const fs::path dir =
        simulated(root / fmt::format("stack{}", black_level), sim::NoiseModel::kPhysical, black_level);
    for (const char* method : {"robust", "biquadratic"}) {
      SolveSettings settings;
      settings.method = method;
      settings.threads = 2;
      settings.resolve();
      const double estimated_error = solve_folder(dir, settings, root / "estimated").error->mean;
      settings.shadow_threshold = kMinShadowThreshold;
      settings.resolve();
      const double fixed_error = solve_folder(dir, settings, root / "fixed").error->mean;
      RecordProperty(fmt::format("{}_black{}", method, black_level),
                     fmt::format("estimated {:.3f}, 1e-6 {:.3f}", estimated_error, fixed_error));
      EXPECT_LE(estimated_error, fixed_error + 0.01) << method << " black level " << black_level;
    }
  }
}

}  // namespace
}  // namespace lightstage::pipeline
