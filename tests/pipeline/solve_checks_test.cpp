// What `solve` refuses, warns about and corrects around a method
// (solve_checks.hpp): lights of rank < 3, a solve that solved no pixel,
// methods used outside their assumptions, normals facing away.
#include "lightstage/pipeline/solve_checks.hpp"

#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/pipeline/simulate_folder.hpp"
#include "lightstage/pipeline/solve_folder.hpp"
#include "lightstage/pipeline/solve_methods.hpp"
#include "lightstage/pipeline/synthetic_observations.hpp"
#include "lightstage/sim/material.hpp"
#include "lightstage/testing/errors.hpp"
#include "lightstage/testing/paths.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace lightstage::pipeline {
namespace {

namespace fs = std::filesystem;
using testing::error_of;
using ::testing::HasSubstr;

SyntheticScene lambert_scene(const Eigen::MatrixX3d& lights) {
  SyntheticOptions options;
  options.scale = 0.5;
  return render_synthetic(
      sim::parse_material("lambert"), cv::Size(12, 8),
      [](int x, int y) {
        return direction_from_elevation_azimuth(rad_from_deg(40 + 6.0 * y), rad_from_deg(30.0 * x));
      },
      lights, options);
}

SolveSettings settings_for(const std::string& method) {
  SolveSettings settings;
  settings.method = method;
  settings.threads = 1;
  settings.resolve();
  return settings;
}

TEST(SolveChecks, LightsOfRankBelowThreeAreAnErrorNamingTheCause) {
  // Lights along one arc (the xz plane): rank 2.
  Eigen::MatrixX3d arc(20, 3);
  for (int j = 0; j < 20; ++j) {
    const double a = rad_from_deg(-60 + 6.0 * j);
    arc.row(j) << std::sin(a), 0, std::cos(a);
  }
  const SyntheticScene collinear = lambert_scene(arc);
  for (const char* method : {"l2", "robust", "biquadratic", "monotonic", "auto"}) {
    const std::string message = error_of([&] { solve_with(collinear.observations, settings_for(method)); });
    EXPECT_THAT(message, HasSubstr("light directions: rank 2 < 3")) << method;
    EXPECT_THAT(message, HasSubstr("one plane")) << method;
  }
  const Eigen::MatrixX3d same = Eigen::RowVector3d(0.3, 0.2, 0.9).normalized().replicate(20, 1);
  EXPECT_THAT(error_of([&] { solve_with(lambert_scene(same).observations, settings_for("l2")); }),
              HasSubstr("rank 1 < 3: all 20 lights have the same direction"));
  // A narrow but real cone is not degenerate.
  EXPECT_NO_THROW(
      solve_with(lambert_scene(random_hemisphere_lights(20, std::cos(rad_from_deg(10)), 3)).observations,
                 settings_for("l2")));
}

TEST(SolveChecks, ASolveThatSolvesNoPixelIsAnErrorNotAZeroError) {
  const fs::path dir = testing::scratch_dir();
  sim::SimulateOptions options;
  options.scene = "sphere";
  options.light_model = sim::LightModel::kDistant;
  options.width = options.height = 32;
  options.threads = 2;
  simulate_to_folder(testing::source_dir() / "hw/rigs/sim-dome.yaml", options, dir / "stack");
  // A stack whose frames are all black (the LEDs never fired).
  ImageStack stack = io::load_stack(dir / "stack");
  for (const Frame& frame : stack.frames)
    io::write_png(dir / "stack" / frame.filename, cv::Mat::zeros(frame.image.size(), frame.image.type()));
  for (const char* method : {"robust", "biquadratic"}) {
    const std::string message =
        error_of([&] { solve_folder(dir / "stack", settings_for(method), dir / method); });
    EXPECT_THAT(message, HasSubstr("solved no pixel")) << method;
    EXPECT_THAT(message, HasSubstr("too few observations")) << method;
    EXPECT_FALSE(fs::exists(dir / method / "summary.json")) << method;
  }
}

TEST(SolveChecks, MethodsOutsideTheirAssumptionsAreWarned) {
  const auto cone43 = random_hemisphere_lights(96, std::cos(rad_from_deg(43)), 2);
  const auto hemisphere = random_hemisphere_lights(96, 0.05, 2);
  const auto twelve = random_hemisphere_lights(12, 0.2, 2);
  const auto thirty = random_hemisphere_lights(30, 0.05, 2);
  auto warnings = [](const std::string& method, const Eigen::MatrixX3d& lights) {
    const SolveResult result = solve_with(lambert_scene(lights).observations, settings_for(method));
    std::string all;
    for (const auto& w : result.parameters.value("warnings", nlohmann::json::array()))
      all += w.get<std::string>() + "\n";
    return all;
  };
  EXPECT_THAT(warnings("monotonic", cone43), HasSubstr("monotonic: the lights span only 43 deg"));
  EXPECT_EQ(warnings("monotonic", hemisphere), "");
  EXPECT_THAT(warnings("biquadratic", thirty), HasSubstr("biquadratic: 30 lights, under the 50"));
  EXPECT_EQ(warnings("biquadratic", hemisphere), "");
  EXPECT_THAT(warnings("robust", twelve), HasSubstr("robust: only 12 lights"));
  const std::string automatic = warnings("auto", cone43);
  EXPECT_THAT(automatic, HasSubstr("auto: the lights span only 43 deg"));
  // The least-squares baseline assumes nothing a light set can break.
  EXPECT_EQ(warnings("l2", twelve), "");
}

TEST(SolveChecks, NormalsFacingAwayAreClampedToTheHorizonAndCounted) {
  SolveResult result;
  result.normals = cv::Mat(1, 4, CV_32FC3);
  result.normals.at<cv::Vec3f>(0, 0) = cv::Vec3f(0.6f, 0.f, -0.8f);
  result.normals.at<cv::Vec3f>(0, 1) = cv::Vec3f(0.f, 0.f, -1.f);
  result.normals.at<cv::Vec3f>(0, 2) = cv::Vec3f(0.f, 0.6f, 0.8f);
  result.normals.at<cv::Vec3f>(0, 3) = cv::Vec3f(0.f, 0.f, -1.f);  // not solved: left alone
  result.solved = cv::Mat(1, 4, CV_8UC1, cv::Scalar::all(255));
  result.solved.at<std::uint8_t>(0, 3) = 0;
  EXPECT_EQ(clamp_facing_away(result), 2u);
  EXPECT_EQ(result.normals.at<cv::Vec3f>(0, 0), cv::Vec3f(1.f, 0.f, 0.f));
  EXPECT_EQ(result.normals.at<cv::Vec3f>(0, 1), cv::Vec3f(0.f, 0.f, 1.f));
  EXPECT_EQ(result.normals.at<cv::Vec3f>(0, 2), cv::Vec3f(0.f, 0.6f, 0.8f));
  EXPECT_EQ(result.normals.at<cv::Vec3f>(0, 3), cv::Vec3f(0.f, 0.f, -1.f));
  // solve_with records the count.
  const SolveResult solved =
      solve_with(lambert_scene(random_hemisphere_lights(40, 0.1, 5)).observations, settings_for("l2"));
  EXPECT_EQ(solved.summary.to_json()["facts"]["normals_facing_away"], 0);
}

}  // namespace
}  // namespace lightstage::pipeline
