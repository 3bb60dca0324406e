// Every method's confidence.pfm (normal_confidence.hpp) against its own
// angular error: Spearman's ρ, on a simulated object of several materials
// with the sweep's noise, on the simulator's cast-shadow bunny and on the
// DiLiGenT ball (skipped without ../shared/data). The issue asks for
// ρ ≤ −0.3 for every method on the ball and the multi-material object: met
// on the multi-material object for every method and on the ball for l2 and
// monotonic; the other methods' ball errors sit at the data's own floor and
// are not ordered by any evidence in the pixel (docs/solvers.md). Every
// figure is printed.
#include "lightstage/common/error.hpp"
#include "lightstage/common/rig.hpp"
#include "lightstage/host/eval/angular_error.hpp"
#include "lightstage/host/eval/rank_correlation.hpp"
#include "lightstage/pipeline/solve_folder.hpp"
#include "lightstage/pipeline/solve_methods.hpp"
#include "lightstage/pipeline/synthetic_observations.hpp"
#include "lightstage/sim/material.hpp"
#include "lightstage/sim/simulate.hpp"
#include "lightstage/testing/paths.hpp"
#include "lightstage/testing/sanitizers.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

namespace lightstage::pipeline {
namespace {

namespace fs = std::filesystem;

const std::vector<std::string>& per_pixel_methods() {
  static const std::vector<std::string> methods = {"l2",   "robust", "monotonic", "bilinear", "biquadratic",
                                                   "auto", "rpca",   "l1",        "sbl"};
  return methods;
}

double rho_against_error(const SolveResult& result, const cv::Mat& truth, const cv::Mat& mask) {
  const AngularErrorMap error = angular_error(result.normals, truth, mask);
  EXPECT_EQ(result.confidence.size(), result.normals.size());
  return spearman_rho(result.confidence, error.degrees, error.valid);
}

TEST(Confidence, RanksTiesAndConstantsAsSpearmanDefines) {
  EXPECT_DOUBLE_EQ(spearman_rho({1, 2, 3, 4}, {10, 20, 30, 40}), 1.0);
  EXPECT_DOUBLE_EQ(spearman_rho({1, 2, 3, 4}, {9, 4, 1, 0}), -1.0);
  // Monotonic but not linear: still 1.
  EXPECT_DOUBLE_EQ(spearman_rho({1, 2, 3, 4}, {1, 8, 27, 1000}), 1.0);
  // Ties share their mean rank: ranks (1.5, 1.5, 3) against (1, 2, 3).
  EXPECT_NEAR(spearman_rho({5, 5, 7}, {1, 2, 3}), 0.8660254, 1e-6);
  EXPECT_EQ(spearman_rho({2, 2, 2}, {1, 2, 3}), 0.0);
  EXPECT_THROW(spearman_rho({1, 2}, {1, 2, 3}), InputError);
  EXPECT_THROW(spearman_rho({1}, {1}), InputError);
}

// Four materials side by side over the same grid of normals, 16-bit noise.
SyntheticScene multi_material_scene() {
  const char* materials[] = {"lambert", "cook-torrance:roughness=0.3,ks=0.5", "ward:alpha=0.2,ks=0.5",
                             "oren-nayar:sigma=0.3"};
  const int width = 16, height = 12, count = 4;
  const Eigen::MatrixX3d lights = random_hemisphere_lights(60, 0.1, 11);
  SyntheticScene scene;
  Observations& obs = scene.observations;
  obs.size = cv::Size(width * count, height);
  obs.lights = lights;
  obs.mask = cv::Mat(obs.size, CV_8UC1, cv::Scalar::all(255));
  scene.truth = cv::Mat(obs.size, CV_32FC3, cv::Scalar::all(0));
  std::vector<SyntheticScene> parts;
  for (int m = 0; m < count; ++m) {
    SyntheticOptions options;
    options.scale = 0.5;
    options.noise = 0.05;
    options.seed = 3 + static_cast<unsigned>(m);
    parts.push_back(render_synthetic(
        sim::parse_material(materials[m]), cv::Size(width, height),
        [&](int x, int y) {
          const double azimuth = 2 * kPi * (x + 0.5) / width;
          return direction_from_elevation_azimuth(rad_from_deg(12 + 76.0 * (y + 0.5) / height), azimuth);
        },
        lights, options));
  }
  const auto images = lights.rows();
  obs.intensities.resize(static_cast<Eigen::Index>(width * count * height), images);
  obs.saturated = FlagMatrix::Constant(obs.intensities.rows(), images, false);
  for (int y = 0; y < height; ++y) {
    for (int m = 0; m < count; ++m) {
      const Observations& part = parts[static_cast<std::size_t>(m)].observations;
      for (int x = 0; x < width; ++x) {
        const auto row = static_cast<Eigen::Index>(obs.pixels.size());
        const auto source = static_cast<Eigen::Index>(y * width + x);
        EXPECT_EQ(part.pixels[static_cast<std::size_t>(source)], cv::Point(x, y));
        obs.pixels.emplace_back(m * width + x, y);
        obs.intensities.row(row) = part.intensities.row(source);
        obs.saturated.row(row) = part.saturated.row(source);
        scene.truth.at<cv::Vec3f>(y, m * width + x) =
            parts[static_cast<std::size_t>(m)].truth.at<cv::Vec3f>(y, x);
      }
    }
  }
  return scene;
}

TEST(Confidence, OrdersTheErrorOfEveryMethodOnSeveralNoisyMaterials) {
  const SyntheticScene scene = multi_material_scene();
  for (const auto& method : per_pixel_methods()) {
    SolveSettings settings;
    settings.method = method;
    settings.threads = 2;
    settings.resolve();
    const SolveResult result = solve_with(scene.observations, settings);
    const double rho = rho_against_error(result, scene.truth, scene.observations.mask);
    std::printf("multi-material %-12s rho %+.3f\n", method.c_str(), rho);
    RecordProperty(method, fmt::format("{:.3f}", rho));
    // Less confident where the error is larger, for every method.
    EXPECT_LE(rho, -0.3) << method;
    if (method == "l2" || method == "robust" || method == "l1") {
      EXPECT_LE(rho, -0.45) << method;
    }
    EXPECT_EQ(result.parameters["confidence"]["model"], "lambertian sandwich and disagreement") << method;
    if (method != "auto") continue;
    // auto says which answer each pixel took, and counts them.
    ASSERT_EQ(result.choice.size(), result.normals.size());
    EXPECT_EQ(result.choices.size(), 4u);
    EXPECT_EQ(static_cast<std::size_t>(cv::countNonZero(result.choice)), result.summary.pixels_solved);
    std::size_t counted = 0;
    for (const auto& fact : result.summary.findings)
      if (fact.key == "method_counts")
        for (const auto& [name, count] : fact.value.items()) counted += count.get<std::size_t>();
    EXPECT_EQ(counted, result.summary.pixels_solved);
  }
}

// Cast shadows over a floor: errors from lights the object hides.
TEST(Confidence, OrdersTheErrorOfEveryMethodUnderCastShadows) {
  LIGHTSTAGE_MEASURED_IN_RELEASE_ONLY("Confidence.OrdersTheErrorOfEveryMethodOnSeveralNoisyMaterials");
  sim::SimulateOptions options;
  options.scene = "bunny-shadows";
  options.light_model = sim::LightModel::kDistant;
  options.width = options.height = 64;
  options.threads = 2;
  const ImageStack stack = sim::simulate_stack(load_rig(default_rig_path()), options);
  const Observations observations = make_observations(stack);
  for (const auto& method : per_pixel_methods()) {
    SolveSettings settings;
    settings.method = method;
    settings.threads = 2;
    settings.resolve();
    const SolveResult result = solve_with(observations, settings);
    const double rho = rho_against_error(result, stack.ground_truth->normals, stack.mask);
    std::printf("bunny-shadows %-12s rho %+.3f\n", method.c_str(), rho);
    RecordProperty(method, fmt::format("{:.3f}", rho));
    EXPECT_LE(rho, -0.15) << method;
  }
}

TEST(Confidence, OrdersTheErrorOfL2AndMonotonicOnTheDiligentBall) {
  LIGHTSTAGE_MEASURED_IN_RELEASE_ONLY("Confidence.OrdersTheErrorOfEveryMethodOnSeveralNoisyMaterials");
  const auto shared = testing::shared_data_dir();
  if (shared.empty() || !fs::exists(shared / "diligent/ballPNG")) GTEST_SKIP() << "shared data not found";
  const SolveInput input = load_solve_input(shared / "diligent/ballPNG", RadiometryOptions{});
  ASSERT_TRUE(input.ground_truth.has_value());
  for (const auto& method : per_pixel_methods()) {
    SolveSettings settings;
    settings.method = method;
    settings.threads = 2;
    settings.resolve();
    const SolveResult result = solve_with(input.observations, settings, input.shadow);
    const double rho = rho_against_error(result, input.ground_truth->normals, input.observations.mask);
    std::printf("ball %-12s rho %+.3f\n", method.c_str(), rho);
    RecordProperty(method, fmt::format("{:.3f}", rho));
    if (method == "l2" || method == "monotonic") {
      EXPECT_LE(rho, -0.45) << method;
    }
    EXPECT_EQ(result.parameters["confidence"]["scale_deg"], 1.0) << method;
  }
}

}  // namespace
}  // namespace lightstage::pipeline
