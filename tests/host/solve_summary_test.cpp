// SolveSummary: the one formatter of the solvers' message, the usable /
// unusable verdict for each of its cases and its JSON, and every solver
// filling the summary on a tiny synthetic solve.
#include "lightstage/host/solvers/auto.hpp"
#include "lightstage/host/solvers/bipolynomial.hpp"
#include "lightstage/host/solvers/lambertian.hpp"
#include "lightstage/host/solvers/monotonic.hpp"
#include "lightstage/host/solvers/robust.hpp"
#include "lightstage/host/solvers/shape_prior.hpp"
#include "lightstage/host/solvers/solve_result.hpp"
#include "reflectance_scene.hpp"
#include "synthetic.hpp"

#include <gtest/gtest.h>

#include <string>

namespace lightstage {
namespace {

using testing::hemisphere_lights;
using testing::make_reflectance_scene;

SolveSummary counts(std::size_t in_mask, std::size_t solved, std::size_t too_few, std::size_t degenerate) {
  SolveSummary s;
  s.method = "l2";
  s.pixels_in_mask = in_mask;
  s.pixels_solved = solved;
  s.pixels_rejected_too_few_observations = too_few;
  s.pixels_rejected_degenerate = degenerate;
  s.seconds = 1.234;
  return s;
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(SolveSummaryMessage, ShowsSettingsCountsSecondsFindingsAndRejections) {
  SolveSummary s = counts(100, 90, 6, 4);
  s.method = "robust";
  s.settings = {{"estimator", "irls-l1", "irls-l1"}, {"t_low", 0.5, "T_low 50%"}, {"hidden", 1, ""}};
  s.findings = {{"mean_iterations", 3.25, "3.2 iterations on average"}};
  EXPECT_EQ(
      s.format_message(),
      "robust (irls-l1, T_low 50%): solved 90 of 100 pixels in 1.23 s, 3.2 iterations on average (6 too "
      "few observations, 4 degenerate)");
}

TEST(SolveSummaryMessage, WithoutFactsHasNoParentheses) {
  EXPECT_EQ(counts(10, 10, 0, 0).format_message(),
            "l2: solved 10 of 10 pixels in 1.23 s (0 too few observations, 0 degenerate)");
}

TEST(SolveSummaryMessage, EndsWithTheReasonWhenNotUsable) {
  const SolveSummary s = counts(10, 0, 0, 10);
  const std::string message = s.format_message();
  EXPECT_NE(message.find("; not usable: " + s.unusable_reason()), std::string::npos) << message;
}

TEST(SolveSummaryVerdict, UsableWhenEnoughPixelsAreSolved) {
  const SolveSummary s = counts(100, 60, 30, 10);
  EXPECT_TRUE(s.usable());
  EXPECT_EQ(s.unusable_reason(), "");
}

TEST(SolveSummaryVerdict, EmptyMask) {
  const SolveSummary s = counts(0, 0, 0, 0);
  EXPECT_FALSE(s.usable());
  EXPECT_TRUE(contains(s.unusable_reason(), "mask is empty")) << s.unusable_reason();
}

TEST(SolveSummaryVerdict, DegenerateLightsWhenEveryPixelIsDegenerate) {
  const SolveSummary s = counts(50, 0, 0, 50);
  EXPECT_FALSE(s.usable());
  EXPECT_TRUE(contains(s.unusable_reason(), "lights are degenerate")) << s.unusable_reason();
}

TEST(SolveSummaryVerdict, EveryPixelShortOfObservations) {
  const SolveSummary s = counts(50, 0, 50, 0);
  EXPECT_FALSE(s.usable());
  EXPECT_TRUE(contains(s.unusable_reason(), "too few observations")) << s.unusable_reason();
}

TEST(SolveSummaryVerdict, NoPixelSolvedForMixedReasons) {
  const SolveSummary s = counts(50, 0, 20, 30);
  EXPECT_FALSE(s.usable());
  EXPECT_TRUE(contains(s.unusable_reason(), "no pixel was solved (20 too few observations, 30 degenerate)"))
      << s.unusable_reason();
}

TEST(SolveSummaryVerdict, BelowTheSolvedFractionFloor) {
  ASSERT_DOUBLE_EQ(SolveSummary::kMinUsableFraction, 0.01);
  const SolveSummary below = counts(1000, 9, 991, 0);
  EXPECT_FALSE(below.usable());
  EXPECT_TRUE(contains(below.unusable_reason(), "only 9 of 1000 pixels")) << below.unusable_reason();
  EXPECT_TRUE(contains(below.unusable_reason(), "1% floor")) << below.unusable_reason();
  EXPECT_TRUE(counts(1000, 10, 990, 0).usable());  // exactly at the floor
}

TEST(SolveSummaryJson, CarriesTheVerdictTheMessageAndTheFacts) {
  SolveSummary s = counts(100, 100, 0, 0);
  s.settings = {{"t_low", 0.5, "T_low 50%"}};
  s.findings = {{"mean_iterations", 3.0, "3.0 iterations on average"}};
  const nlohmann::json good = s.to_json();
  EXPECT_EQ(good["usable"], true);
  EXPECT_FALSE(good.contains("unusable_reason"));
  EXPECT_EQ(good["message"], s.format_message());
  EXPECT_EQ(good["facts"], (nlohmann::json{{"t_low", 0.5}, {"mean_iterations", 3.0}}));
  EXPECT_EQ(good["pixels_solved"], 100);

  const SolveSummary bad = counts(100, 0, 0, 100);
  const nlohmann::json j = bad.to_json();
  EXPECT_EQ(j["usable"], false);
  EXPECT_EQ(j["unusable_reason"], bad.unusable_reason());
  EXPECT_EQ(j["facts"], nlohmann::json::object());
}

// What every solver's summary holds after a solve that worked.
void expect_filled(const SolveSummary& s, const std::string& method, std::size_t pixels) {
  EXPECT_EQ(s.method, method);
  EXPECT_EQ(s.pixels_in_mask, pixels);
  EXPECT_EQ(s.pixels_solved + s.pixels_rejected_too_few_observations + s.pixels_rejected_degenerate, pixels);
  EXPECT_GT(s.pixels_solved, pixels / 2) << s.message;
  EXPECT_GE(s.seconds, 0.0);
  EXPECT_FALSE(s.settings.empty()) << method;
  EXPECT_EQ(s.message, s.format_message());
  EXPECT_EQ(s.message.rfind(method + " (", 0), 0u) << s.message;
  EXPECT_TRUE(s.usable()) << s.message;
  const nlohmann::json j = s.to_json();
  EXPECT_EQ(j["usable"], true);
  for (const auto& fact : s.settings) EXPECT_TRUE(j["facts"].contains(fact.key)) << fact.key;
  for (const auto& fact : s.findings) EXPECT_TRUE(j["facts"].contains(fact.key)) << fact.key;
}

TEST(SolversFillTheSummary, L2) {
  const auto scene = testing::make_scene(6, 5, 8, 3, false);
  const SolveSummary s = solve_lambertian(scene.observations).summary;
  expect_filled(s, "l2", 30);
  EXPECT_EQ(s.pixels_solved, 30u);
  EXPECT_EQ(s.to_json()["facts"]["mode"], "all");
  EXPECT_TRUE(contains(s.message, "l2 (all observations, one pseudo-inverse): solved 30 of 30 pixels"))
      << s.message;
}

TEST(SolversFillTheSummary, L2WithCoplanarLightsIsNotUsable) {
  auto scene = testing::make_scene(4, 4, 6, 5, false);
  scene.observations.lights.col(2).setZero();  // every light in the image plane
  const SolveSummary s = solve_lambertian(scene.observations).summary;
  EXPECT_EQ(s.pixels_rejected_degenerate, 16u);
  EXPECT_FALSE(s.usable());
  EXPECT_TRUE(contains(s.unusable_reason(), "lights are degenerate")) << s.unusable_reason();
  EXPECT_EQ(s.to_json()["usable"], false);
  EXPECT_TRUE(contains(s.message, "not usable")) << s.message;
}

TEST(SolversFillTheSummary, Robust) {
  const auto scene = make_reflectance_scene("lambert", hemisphere_lights(30, 3), 6, 4);
  RobustOptions options;
  options.threads = 2;
  const SolveSummary s = solve_robust(scene.observations, options).summary;
  expect_filled(s, "robust", 24);
  EXPECT_EQ(s.to_json()["facts"]["t_low"], options.t_low);
  EXPECT_TRUE(contains(s.message, "T_low 50%")) << s.message;
}

TEST(SolversFillTheSummary, Monotonic) {
  const auto scene = make_reflectance_scene("lambert", hemisphere_lights(30, 3), 6, 4);
  MonotonicOptions options;
  options.threads = 2;
  const SolveSummary s = solve_monotonic(scene.observations, options).summary;
  expect_filled(s, "monotonic", 24);
  EXPECT_EQ(s.to_json()["facts"]["azimuth"], "isotropy");
  EXPECT_TRUE(contains(s.message, "azimuth from isotropy")) << s.message;
}

TEST(SolversFillTheSummary, BiPolynomial) {
  const auto scene = make_reflectance_scene("lambert", hemisphere_lights(30, 3), 6, 4);
  BiPolynomialOptions options;
  options.threads = 2;
  const SolveSummary s = solve_bipolynomial(scene.observations, options).summary;
  expect_filled(s, "biquadratic", 24);
  const nlohmann::json facts = s.to_json()["facts"];
  EXPECT_TRUE(facts.contains("falloff_estimated"));
  EXPECT_GT(facts["mean_iterations"].get<double>(), 0.0);
  EXPECT_TRUE(contains(s.message, "iterations on average")) << s.message;
  EXPECT_TRUE(contains(s.message, "fall-off")) << s.message;
}

TEST(SolversFillTheSummary, Auto) {
  const auto scene = make_reflectance_scene("lambert", hemisphere_lights(30, 3), 6, 4);
  AutoOptions options;
  options.threads = 2;
  const SolveSummary s = solve_auto(scene.observations, options).summary;
  expect_filled(s, "auto", 24);
  EXPECT_EQ(s.to_json()["facts"]["models"], (nlohmann::json{"biquadratic", "monotonic"}));
  EXPECT_TRUE(contains(s.message, "auto (biquadratic + monotonic): solved")) << s.message;
}

TEST(SolversFillTheSummary, ShapePrior) {
  // Attached shadows make the images span more than the 3 dimensions of
  // unshadowed Lambertian shading, as k = 9 needs.
  const auto scene = make_reflectance_scene("lambert", hemisphere_lights(24, 5), 12, 8);
  ShapePriorOptions options;
  options.max_evaluations = 200;
  const SolveSummary s = solve_shape_prior(scene.observations, scene.truth, {}, options).summary;
  expect_filled(s, "shape-prior", 96);
  const nlohmann::json facts = s.to_json()["facts"];
  EXPECT_EQ(facts["k"], 9);
  EXPECT_TRUE(facts["prior_fit_cost"].contains("refined"));
  EXPECT_TRUE(contains(s.message, "shape-prior (k = 9): solved")) << s.message;
  EXPECT_TRUE(contains(s.message, "prior fit cost")) << s.message;
}

}  // namespace
}  // namespace lightstage
