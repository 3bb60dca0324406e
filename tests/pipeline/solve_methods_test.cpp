#include "lightstage/pipeline/solve_methods.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/eval/angular_error.hpp"
#include "lightstage/pipeline/synthetic_observations.hpp"
#include "lightstage/sim/material.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace lightstage::pipeline {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

SyntheticScene lambert_scene() {
  SyntheticOptions options;
  options.scale = 0.5;
  return render_synthetic(
      sim::parse_material("lambert"), cv::Size(12, 8),
      [](int x, int y) {
        return direction_from_elevation_azimuth(rad_from_deg(20 + 8.0 * y), rad_from_deg(30.0 * x));
      },
      random_hemisphere_lights(40, 0.1, 5), options);
}

TEST(SolveMethods, ListsEveryMethodInHelpOrder) {
  EXPECT_THAT(solve_method_names(), ElementsAre("l2", "robust", "monotonic", "bilinear", "biquadratic",
                                                "bicubic", "auto", "rpca", "l1", "sbl", "shape-prior"));
  for (const auto& method : solve_methods()) EXPECT_FALSE(method.help.empty()) << method.name;
}

TEST(SolveMethods, AnUnknownNameIsRefusedWithTheKnownOnes) {
  try {
    find_solve_method("lambertian");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("--method: unknown method 'lambertian'"));
    EXPECT_THAT(e.what(), HasSubstr("l2, robust"));
  }
  SolveSettings settings;
  settings.method = "lambertian";
  EXPECT_THROW(settings.resolve(), InputError);
}

TEST(SolveMethods, EveryPerPixelMethodSolvesALambertianScene) {
  const SyntheticScene scene = lambert_scene();
  for (const std::string name : {"l2", "robust", "monotonic", "bilinear", "biquadratic", "bicubic", "auto"}) {
    SolveSettings settings;
    settings.method = name;
    settings.threads = 1;
    settings.shadow_threshold = 1e-6;  // l2 keeps the attached shadows otherwise
    settings.resolve();
    const SolveResult result = solve_with(scene.observations, settings);
    const auto error = angular_error(result.normals, scene.truth, scene.observations.mask).stats;
    EXPECT_EQ(error.count, 96u) << name;
    EXPECT_LT(error.mean, 2.0) << name;
  }
}

TEST(SolveMethods, MonotonicTakesItsAzimuthFromTheNamedMethod) {
  const SyntheticScene scene = lambert_scene();
  SolveSettings settings;
  settings.method = "monotonic";
  settings.azimuth_from = "l2";
  settings.resolve();
  EXPECT_EQ(solve_with(scene.observations, settings).parameters["azimuth"], "l2");
  settings.azimuth_from = "monotonic";
  EXPECT_THROW(solve_with(scene.observations, settings), InputError);
  settings.azimuth_from = "nothing";
  EXPECT_THROW(settings.resolve(), InputError);
}

TEST(SolveMethods, ShapePriorWithoutAPriorNamesTheFlag) {
  SolveSettings settings;
  settings.method = "shape-prior";
  settings.resolve();
  try {
    solve_with(lambert_scene().observations, settings);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("--prior"));
  }
}

TEST(SolveMethods, ARegisteredMethodIsFoundAndSolvesWithTheSettings) {
  register_solve_method(
      {"test-flat", "every normal faces the camera", [](const Observations& obs, const SolveSettings& s) {
         SolveResult result = solve_lambertian(obs, s.l2);
         result.normals.setTo(cv::Scalar(0, 0, 1), result.solved);
         result.summary.method = "test-flat";
         return result;
       }});
  EXPECT_EQ(solve_method_names().back(), "test-flat");
  SolveSettings settings;
  settings.method = "test-flat";
  settings.resolve();
  const SolveResult result = solve_with(lambert_scene().observations, settings);
  EXPECT_EQ(result.summary.method, "test-flat");
  EXPECT_EQ(result.normals.at<cv::Vec3f>(3, 3), cv::Vec3f(0, 0, 1));
  // A name is registered once; an entry needs a name and a function.
  EXPECT_THROW(register_solve_method({"test-flat", "again", solve_methods().front().solve}), InputError);
  EXPECT_THROW(register_solve_method({"", "no name", solve_methods().front().solve}), InputError);
  EXPECT_THROW(register_solve_method({"test-empty", "no function", {}}), InputError);
}

TEST(SolveSettings, SharedSettingsReachEveryMethodsOptions) {
  SolveSettings settings;
  settings.method = "biquadratic";
  settings.shadow_threshold = 0.02;
  settings.t_low = 0.3;
  settings.min_observations = 7;
  settings.max_iterations = 12;
  settings.threads = 1;
  settings.falloff = "0.25";
  settings.no_clamp = true;
  settings.resolve();
  EXPECT_EQ(settings.l2.shadow_threshold, 0.02);
  EXPECT_EQ(settings.robust.shadow_threshold, 0.02);
  EXPECT_EQ(settings.monotonic.shadow_threshold, 0.02);
  EXPECT_EQ(settings.bipolynomial.shadow_threshold, 0.02);
  EXPECT_EQ(settings.automatic.bipolynomial.shadow_threshold, 0.02);
  EXPECT_EQ(settings.automatic.monotonic.shadow_threshold, 0.02);
  EXPECT_EQ(settings.bipolynomial.t_low, 0.3);
  EXPECT_EQ(settings.robust.min_observations, 7);
  EXPECT_EQ(settings.automatic.bipolynomial.max_iterations, 12);
  EXPECT_EQ(settings.bipolynomial.threads, 1);
  ASSERT_TRUE(settings.bipolynomial.falloff.has_value());
  EXPECT_EQ(*settings.bipolynomial.falloff, 0.25);
  EXPECT_FALSE(settings.radiometry.clamp_to_one);
}

TEST(SolveSettings, TheChosenMethodsBadValuesFailAtResolve) {
  SolveSettings settings;
  settings.method = "biquadratic";
  settings.shadow_threshold = -1;  // l2 takes it; the bi-polynomial refuses it
  EXPECT_THROW(settings.resolve(), InputError);
  settings.method = "l2";
  EXPECT_NO_THROW(settings.resolve());
  settings.falloff = "steep";
  EXPECT_THROW(settings.resolve(), InputError);
  settings.falloff = "auto";
  settings.estimator = "median";
  EXPECT_THROW(settings.resolve(), InputError);
}

TEST(SolveSettings, FalloffParsesAutoAndNumbersInRange) {
  EXPECT_FALSE(parse_falloff("auto").has_value());
  EXPECT_EQ(parse_falloff("+0.3"), 0.3);
  EXPECT_EQ(parse_falloff("0"), 0.0);
  for (const char* bad : {"7", "-0.51", "steep", "", "inf", "0.3x"})
    EXPECT_THROW(parse_falloff(bad), InputError) << bad;
}

TEST(SolveWork, CountsPixelsPassesAndEvaluations) {
  const SyntheticScene scene = lambert_scene();
  SolveSettings settings;
  EXPECT_EQ(solve_work(settings, scene.observations).total, 96u);
  settings.method = "monotonic";
  EXPECT_EQ(solve_work(settings, scene.observations).total, 192u);  // the azimuth method's pass first
  settings.azimuth_from = "isotropy";
  EXPECT_EQ(solve_work(settings, scene.observations).total, 96u);
  settings.method = "shape-prior";
  const SolveWork work = solve_work(settings, scene.observations);
  EXPECT_EQ(work.unit, "evaluations");
  EXPECT_EQ(work.total, static_cast<std::size_t>(settings.shape_prior.options.max_evaluations));
}

}  // namespace
}  // namespace lightstage::pipeline
