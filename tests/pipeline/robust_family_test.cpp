// The published robust family (rpca, l1, sbl) against the default robust
// method on the simulator's robust-family objects: the bunny on a floor with
// strong cast shadows (Lambertian) and the same with a sharp specular lobe,
// 64x64 under the 96-LED dome, with distant lights and with the simulator's
// default near ones, solved as `solve --method M` would (the shadow threshold
// estimated from the data: its clipped-noise estimate is what takes every
// method here from degrees to tenths of one). Robust, l1 and sbl must reach
// tenths of a degree (rpca within 1.5°, 2.5° near; auto within 0.5°, 1.2°
// near), and the default robust must beat every member of the family by the
// issue's 10% (with distant lights on the cast-shadow bunny 0.103 against
// 0.9 × sbl's 0.117: a thin margin, the same with seeds 2-4).
#include "lightstage/host/eval/angular_error.hpp"
#include "lightstage/pipeline/simulate_folder.hpp"
#include "lightstage/pipeline/solve_folder.hpp"
#include "lightstage/pipeline/solve_methods.hpp"
#include "lightstage/sim/simulate.hpp"
#include "lightstage/testing/paths.hpp"
#include "lightstage/testing/sanitizers.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <tuple>

namespace lightstage::pipeline {
namespace {

// The stack `solve` reads: near lights from the LED positions its manifest holds.
SolveInput render(const std::string& scene, sim::LightModel lights) {
  sim::SimulateOptions options;
  options.scene = scene;
  options.light_model = lights;
  options.width = options.height = 64;
  options.threads = 2;
  const std::filesystem::path dir =
      testing::scratch_dir() /
      fmt::format("{}-{}", scene, lights == sim::LightModel::kNear ? "near" : "distant");
  simulate_to_folder(testing::source_dir() / "hw/rigs/sim-dome.yaml", options, dir);
  SolveInput input = load_solve_input(dir, {});
  EXPECT_EQ(input.observations.near.has_value(), lights == sim::LightModel::kNear);
  return input;
}

double mean_error(const SolveInput& input, const std::string& method) {
  SolveSettings settings;
  settings.method = method;
  settings.threads = 2;
  settings.resolve();
  const SolveResult result = solve_with(input.observations, settings, input.shadow);
  return angular_error(result.normals, input.ground_truth->normals, input.observations.mask).stats.mean;
}

using Object = std::tuple<std::string, sim::LightModel>;

class RobustFamily : public ::testing::TestWithParam<Object> {};

TEST_P(RobustFamily, RobustLeadsEveryMemberOfTheFamilyByTenPercent) {
  LIGHTSTAGE_MEASURED_IN_RELEASE_ONLY("test_host_robust_family_solvers");
  const auto& [scene, lights] = GetParam();
  const bool near = lights == sim::LightModel::kNear;
  const SolveInput input = render(scene, lights);
  ASSERT_TRUE(input.ground_truth.has_value());
  std::map<std::string, double> errors;
  for (const std::string method : {"l2", "robust", "rpca", "l1", "sbl", "auto"}) {
    errors[method] = mean_error(input, method);
    RecordProperty(method, fmt::format("{:.3f}", errors[method]));
    std::printf("%s %s %s: mean %.3f deg\n", scene.c_str(), near ? "near" : "distant", method.c_str(),
                errors[method]);
  }
  for (const std::string method : {"rpca", "l1", "sbl"}) {
    // Every member of the family is itself robust: better than plain least squares.
    EXPECT_LT(errors[method], errors["l2"]) << method;
    // The lead: the default robust method 10% ahead of each.
    EXPECT_LE(errors["robust"], 0.9 * errors[method]) << method;
  }
  // Near lights on a guessed surface (a plane) cost every method: the light model is off at grazing light.
  EXPECT_LE(errors["robust"], near ? 0.3 : 0.15);
  EXPECT_LE(errors["l1"], near ? 0.6 : 0.3);
  EXPECT_LE(errors["sbl"], near ? 0.7 : 0.3);
  EXPECT_LE(errors["rpca"], near ? 2.5 : 1.5);
  EXPECT_LE(errors["auto"], near ? 1.2 : 0.5);
}

INSTANTIATE_TEST_SUITE_P(Objects, RobustFamily,
                         ::testing::Combine(::testing::Values("bunny-shadows", "bunny-specular"),
                                            ::testing::Values(sim::LightModel::kDistant,
                                                              sim::LightModel::kNear)),
                         [](const auto& object) {
                           std::string name = std::get<0>(object.param);
                           std::erase(name, '-');
                           return name +
                                  (std::get<1>(object.param) == sim::LightModel::kNear ? "Near" : "Distant");
                         });

}  // namespace
}  // namespace lightstage::pipeline
