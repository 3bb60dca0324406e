// Light calibration measured against the simulator's known lights: chrome
// spheres rendered on the default dome (hw/rigs/sim-dome.yaml, 96 LEDs,
// 400 mm radius) and written to stack folders as a capture would be, then
// calibrated from the folders alone. Thresholds are the issue's: mean
// direction error < 0.1°, max < 0.3°; LED positions within 1% of the radius.
#include "lightstage/common/error.hpp"
#include "lightstage/common/rig.hpp"
#include "lightstage/host/calibration/apply_calibration.hpp"
#include "lightstage/host/calibration/calibrate_lights.hpp"
#include "lightstage/host/eval/angular_error.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/solvers/lambertian.hpp"
#include "lightstage/sim/simulate.hpp"
#include "lightstage/testing/errors.hpp"
#include "lightstage/testing/paths.hpp"
#include "lightstage/testing/sanitizers.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

namespace lightstage::calibration {
namespace {

namespace fs = std::filesystem;
using testing::error_of;

struct DirectionErrors {
  double mean = 0, max = 0;
};

// Simulates `scene` on `rig` and writes it as a stack folder with the
// simulator's manifest (camera included), as `lightstage simulate` does.
ImageStack write_sim_stack(const Rig& rig, const std::string& scene, sim::LightModel model,
                           const fs::path& dir, std::optional<int> width = std::nullopt,
                           std::optional<double> exposure_us = std::nullopt) {
  sim::SimulateOptions o;
  o.scene = scene;
  o.light_model = model;
  o.width = width;
  o.height = width;
  o.sensor.exposure_us = exposure_us;
  o.threads = 0;
  const ImageStack stack = sim::simulate_stack(rig, o);
  io::write_stack(dir, stack, {{"simulation", sim::describe(rig, o)}});
  return stack;
}

fs::path scene_file(const fs::path& dir, const std::string& name, const std::string& yaml) {
  const fs::path path = dir / (name + ".yaml");
  std::ofstream(path) << yaml;
  return path;
}

std::string chrome_sphere_yaml(double radius, const Vec3& centre) {
  return fmt::format(
      "name: chrome\nobject: {{type: sphere, radius_mm: {}, center_mm: [{}, {}, {}]}}\nmaterial: chrome\n"
      "environment_radiance: 0.05\n",
      radius, centre.x(), centre.y(), centre.z());
}

// Calibrated directions against the rig's true ones (from the object position).
DirectionErrors direction_errors(const LightCalibration& cal, const Rig& rig) {
  DirectionErrors e;
  EXPECT_EQ(cal.lights.size(), rig.leds.size());
  for (std::size_t i = 0; i < cal.lights.size(); ++i) {
    EXPECT_TRUE(cal.lights[i].measured) << cal.lights[i].image;
    const double angle = angle_between_deg(cal.lights[i].direction, rig.light_direction(rig.leds[i]));
    e.mean += angle / static_cast<double>(cal.lights.size());
    e.max = std::max(e.max, angle);
  }
  return e;
}

class CalibrationSim : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { rig_ = new Rig(load_rig(default_rig_path())); }
  static void TearDownTestSuite() { delete rig_; }
  static Rig* rig_;
};
Rig* CalibrationSim::rig_ = nullptr;

// Distant lights: the mirror direction itself is the light direction.
TEST_F(CalibrationSim, DistantChromeSphereDirectionsWithinATenthOfADegree) {
  const fs::path dir = testing::scratch_dir();
  write_sim_stack(*rig_, "chrome-probe", sim::LightModel::kDistant, dir / "chrome");
  fs::remove(dir / "chrome" / "mask.png");  // the outline must come from the images
  LightCalibrationOptions o;
  o.inputs = {dir / "chrome"};
  const auto run = calibrate_lights(o);
  EXPECT_EQ(run.calibration.spheres.front().sphere.circle.source, "image");
  EXPECT_EQ(run.calibration.direction_method, "mirror");
  const DirectionErrors e = direction_errors(run.calibration, *rig_);
  RecordProperty("mean_deg", fmt::format("{:.4f}", e.mean));
  RecordProperty("max_deg", fmt::format("{:.4f}", e.max));
  EXPECT_LT(e.mean, 0.1);
  EXPECT_LT(e.max, 0.3);
  EXPECT_TRUE(run.calibration.problems.empty()) << run.calibration.problems.front();
}

// Near lights (the LEDs 400 mm away, the sphere 40 mm): mirror directions are
// off by degrees; one sphere position plus the dome radius puts them right.
TEST_F(CalibrationSim, NearChromeSphereWithDomeRadiusWithinATenthOfADegree) {
  LIGHTSTAGE_MEASURED_IN_RELEASE_ONLY("CalibrationSim.DistantChromeSphereDirectionsWithinATenthOfADegree");
  const fs::path dir = testing::scratch_dir();
  write_sim_stack(*rig_, "chrome-probe", sim::LightModel::kNear, dir / "chrome");
  LightCalibrationOptions o;
  o.inputs = {dir / "chrome"};
  o.dome_radius_mm = 0;  // distant: the parallax shows
  const DirectionErrors raw = direction_errors(calibrate_lights(o).calibration, *rig_);
  EXPECT_GT(raw.mean, 1.0);
  o.rig = default_rig_path();
  o.dome_radius_mm.reset();
  const auto run = calibrate_lights(o);
  EXPECT_EQ(run.calibration.direction_method, "dome-radius");
  const DirectionErrors e = direction_errors(run.calibration, *rig_);
  RecordProperty("mirror_mean_deg", fmt::format("{:.4f}", raw.mean));
  RecordProperty("mean_deg", fmt::format("{:.4f}", e.mean));
  RecordProperty("max_deg", fmt::format("{:.4f}", e.max));
  EXPECT_LT(e.mean, 0.1);
  EXPECT_LT(e.max, 0.3);
  ASSERT_TRUE(run.calibration.nominal_fit);
  EXPECT_LT(run.calibration.nominal_fit->max_mm, 4.0);
}

// Two sphere positions triangulate every LED without the dome radius, placed
// and exposed as docs/calibration.md recommends: a 25 mm sphere at x = ±25 mm
// (the largest pair that fits the 102 mm field side by side) and frames
// exposed for the highlights (6× the rig's exposure, set for matte objects:
// the brightest highlight peaks at 73% of full scale). At the rig's exposure
// the highlight centres scatter by 0.021 px per axis — the Cramér–Rao bound
// of their shot noise — and the LEDs of the lowest ring along the baseline,
// whose rays meet at under 3°, cannot be placed to 4 mm by any method
// (20 mm spheres at ±30 mm: σ 5.5 mm, worst error 5.7 mm). The reported
// per-LED uncertainty must match the errors.
TEST_F(CalibrationSim, TwoSpherePositionsTriangulateLedsWithinOnePercentOfTheRadius) {
  LIGHTSTAGE_MEASURED_IN_RELEASE_ONLY("CalibrationSim.DistantChromeSphereDirectionsWithinATenthOfADegree");
  const fs::path dir = testing::scratch_dir();
  const fs::path left = scene_file(dir, "left", chrome_sphere_yaml(25, Vec3(-25, 0, 0)));
  const fs::path right = scene_file(dir, "right", chrome_sphere_yaml(25, Vec3(25, 0, 0)));
  const double exposure_us = 6 * rig_->camera.exposure_us;
  write_sim_stack(*rig_, left.string(), sim::LightModel::kNear, dir / "left", std::nullopt, exposure_us);
  write_sim_stack(*rig_, right.string(), sim::LightModel::kNear, dir / "right", std::nullopt, exposure_us);
  LightCalibrationOptions o;
  o.inputs = {dir / "left", dir / "right"};
  o.rig = default_rig_path();
  o.dome_radius_mm = 0;  // no help from the dome radius
  const auto run = calibrate_lights(o);
  const LightCalibration& cal = run.calibration;
  EXPECT_EQ(cal.direction_method, "triangulated");
  double worst = 0, mean = 0, normalised = 0, worst_sigma = 0;
  std::string worst_image;
  for (std::size_t i = 0; i < cal.lights.size(); ++i) {
    const CalibratedLight& light = cal.lights[i];
    ASSERT_TRUE(light.position_mm) << light.image;
    ASSERT_TRUE(light.position_sigma_mm) << light.image;
    const double error = (*light.position_mm - rig_->leds[i].position_mm).norm();
    if (error > worst) worst_image = light.image;
    worst = std::max(worst, error);
    worst_sigma = std::max(worst_sigma, *light.position_sigma_mm);
    mean += error / static_cast<double>(cal.lights.size());
    normalised += std::pow(error / *light.position_sigma_mm, 2) / static_cast<double>(cal.lights.size());
  }
  normalised = std::sqrt(normalised);
  RecordProperty("position_mean_mm", fmt::format("{:.3f}", mean));
  RecordProperty("position_max_mm", fmt::format("{:.3f}", worst));
  RecordProperty("position_max_image", worst_image);
  RecordProperty("position_sigma_max_mm", fmt::format("{:.3f}", worst_sigma));
  RecordProperty("rms_error_over_sigma", fmt::format("{:.3f}", normalised));
  EXPECT_LT(worst, 0.01 * rig_->dome_radius_mm) << "worst: " << worst_image;
  // The reported uncertainty is honest: errors are about one standard deviation.
  EXPECT_GT(normalised, 0.5);
  EXPECT_LT(normalised, 2.0);
  const DirectionErrors e = direction_errors(cal, *rig_);
  RecordProperty("mean_deg", fmt::format("{:.4f}", e.mean));
  RecordProperty("max_deg", fmt::format("{:.4f}", e.max));
  EXPECT_LT(e.mean, 0.1);
  EXPECT_LT(e.max, 0.3);
}

}  // namespace
}  // namespace lightstage::calibration
