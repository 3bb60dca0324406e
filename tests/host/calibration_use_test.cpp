// Light calibration beyond directions, on simulated stacks: bad input named
// in the errors, intensities from a matte sphere and a flat target against
// the rig's true relative intensities, and near-light Lambertian solving
// with calibrated LED positions against distant-light solving.
#include "lightstage/common/error.hpp"
#include "lightstage/common/rig.hpp"
#include "lightstage/host/calibration/apply_calibration.hpp"
#include "lightstage/host/calibration/calibrate_lights.hpp"
#include "lightstage/host/calibration/calibration_output.hpp"
#include "lightstage/host/calibration/light_intensity.hpp"
#include "lightstage/host/eval/angular_error.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/solvers/lambertian.hpp"
#include "lightstage/sim/simulate.hpp"
#include "lightstage/testing/errors.hpp"
#include "lightstage/testing/paths.hpp"

#include <gtest/gtest.h>

namespace lightstage::calibration {
namespace {

namespace fs = std::filesystem;
using testing::error_of;

void write_sim_stack(const Rig& rig, const std::string& scene, const fs::path& dir,
                     std::optional<int> width) {
  sim::SimulateOptions o;
  o.scene = scene;
  o.width = width;
  o.height = width;
  const ImageStack stack = sim::simulate_stack(rig, o);
  io::write_stack(dir, stack, {{"simulation", sim::describe(rig, o)}});
}

// The default dome with uneven LEDs: relative intensities from 0.7 to 1.3.
Rig uneven_rig() {
  Rig rig = load_rig(default_rig_path());
  for (std::size_t i = 0; i < rig.leds.size(); ++i)
    rig.leds[i].relative_intensity = 0.7 + 0.6 * ((i * 7) % 11) / 10.0;
  return rig;
}

double true_relative(const Rig& rig, std::size_t i) {
  double sum = 0;
  for (const auto& led : rig.leds) sum += led.relative_intensity;
  return rig.leds[i].relative_intensity / (sum / static_cast<double>(rig.leds.size()));
}

// Calibrating the default rig's lights from the chrome-sphere stack `chrome`.
LightCalibrationOptions chrome_sphere_options(const fs::path& chrome) {
  LightCalibrationOptions o;
  o.inputs = {chrome};
  o.rig = default_rig_path();
  return o;
}

TEST(CalibrationBadInput, MissingHighlightAndOverexposedFramesAreNamed) {
  const Rig rig = load_rig(default_rig_path());
  const fs::path dir = testing::scratch_dir() / "chrome";
  write_sim_stack(rig, "chrome-probe", dir, 128);
  // 005.png: the LED did not fire (the median image is what the sphere shows without it).
  cv::Mat dark = io::read_image(dir / "004.png");
  dark.setTo(cv::Scalar::all(0));
  io::write_png(dir / "005.png", dark);
  // 007.png: overexposed.
  io::write_png(dir / "007.png", cv::Mat(dark.size(), dark.type(), cv::Scalar::all(65535)));
  LightCalibrationOptions o;
  o.inputs = {dir};
  const std::string message = error_of([&] { calibrate_lights(o); });
  EXPECT_NE(message.find("no usable highlight for 2 of 96 lights (005.png, 007.png)"), std::string::npos)
      << message;
  EXPECT_NE(message.find("005.png: sphere 0: missing"), std::string::npos) << message;
  EXPECT_NE(message.find("007.png: sphere 0: overexposed"), std::string::npos) << message;
  o.allow_missing = true;
  const auto run = calibrate_lights(o);
  EXPECT_FALSE(run.calibration.lights[4].measured);
  EXPECT_FALSE(run.calibration.lights[6].measured);
  EXPECT_TRUE(run.calibration.lights[5].measured);
  EXPECT_EQ(run.calibration.problems.size(), 2u);
}

TEST(CalibrationBadInput, NoSphereIsAClearError) {
  const Rig rig = load_rig(default_rig_path());
  const fs::path dir = testing::scratch_dir() / "empty";
  write_sim_stack(rig, "chrome-sphere", dir, 64);  // a mirror that shows nothing but highlights
  fs::remove(dir / "mask.png");
  for (int i = 1; i <= 96; ++i)
    io::write_png(dir / fmt::format("{:03}.png", i), cv::Mat(64, 64, CV_16UC1, cv::Scalar::all(0)));
  LightCalibrationOptions o;
  o.inputs = {dir};
  const std::string message = error_of([&] { calibrate_lights(o); });
  EXPECT_NE(message.find("median of its 96 images"), std::string::npos) << message;
  EXPECT_NE(message.find("black"), std::string::npos) << message;
  o.inputs = {testing::scratch_dir() / "nowhere"};
  EXPECT_NE(error_of([&] { calibrate_lights(o); }).find("nowhere: no such stack folder"), std::string::npos);
}

TEST(CalibrationIntensity, MatteSphereAndFlatTargetRecoverRelativeIntensities) {
  const Rig rig = uneven_rig();
  const fs::path dir = testing::scratch_dir();
  write_sim_stack(rig, "chrome-probe", dir / "chrome", 256);
  write_sim_stack(rig, "matte-sphere", dir / "matte", 256);
  write_sim_stack(rig, "white-target", dir / "target", 256);
  LightCalibrationOptions o = chrome_sphere_options(dir / "chrome");
  o.intensity_input = dir / "matte";
  o.intensity_target = IntensityTarget::kMatteSphere;
  const auto matte = calibrate_lights(o);
  o.intensity_input = dir / "target";
  o.intensity_target = IntensityTarget::kFlatTarget;
  const auto flat = calibrate_lights(o);
  double worst_matte = 0, worst_flat = 0;
  for (std::size_t i = 0; i < rig.leds.size(); ++i) {
    const double truth = true_relative(rig, i);
    worst_matte = std::max(worst_matte, std::abs(matte.calibration.lights[i].intensity / truth - 1));
    worst_flat = std::max(worst_flat, std::abs(flat.calibration.lights[i].intensity / truth - 1));
  }
  RecordProperty("matte_max_relative_error", fmt::format("{:.4f}", worst_matte));
  RecordProperty("flat_max_relative_error", fmt::format("{:.4f}", worst_flat));
  EXPECT_LT(worst_matte, 0.01);
  EXPECT_LT(worst_flat, 0.01);
  // The simulated target is uniform: its flat field is 1 within noise.
  ASSERT_FALSE(flat.flat_field.empty());
  cv::Scalar mean, spread;
  cv::meanStdDev(flat.flat_field, mean, spread, flat.flat_field > 0);
  EXPECT_NEAR(mean[0], 1.0, 1e-3);
  EXPECT_LT(spread[0], 0.01);
}

TEST(CalibrationBadInput, AnIntensityTargetOfAnotherSizeIsNamed) {
  const Rig rig = load_rig(default_rig_path());
  const fs::path dir = testing::scratch_dir();
  write_sim_stack(rig, "chrome-probe", dir / "chrome", 128);
  write_sim_stack(rig, "matte-sphere", dir / "matte", 64);
  LightCalibrationOptions o = chrome_sphere_options(dir / "chrome");
  o.intensity_input = dir / "matte";
  EXPECT_NE(error_of([&] { calibrate_lights(o); })
                .find("matte: images are 64x64, but the chrome-sphere stack " + (dir / "chrome").string() +
                      " was taken at 128x128"),
            std::string::npos);
}

// A target fitted band by band, its rows read back from disk for every round,
// gives what the target kept in memory gives: the same passes, the same sums.
TEST(CalibrationIntensity, BandsReadAgainEachRoundGiveTheKeptTargetsFit) {
  const Rig rig = uneven_rig();
  const fs::path dir = testing::scratch_dir();
  write_sim_stack(rig, "chrome-probe", dir / "chrome", 128);
  write_sim_stack(rig, "white-target", dir / "target", 128);
  LightCalibrationOptions o = chrome_sphere_options(dir / "chrome");
  const LightCalibration cal = calibrate_lights(o).calibration;
  const LightGeometry geometry = LightGeometry::of(cal);
  const CalibrationImages index = load_calibration_index(dir / "target");
  ASSERT_FALSE(index.mask.empty());
  const TargetSurface surface = TargetSurface::plane(index.mask, cal.camera, cal.object_position_mm.z());
  for (const bool flat : {false, true}) {
    const IntensityResult kept = fit_intensities(index, surface, geometry, flat, {}, 2);
    // A band of one row; the thread count does not change the sums either.
    const IntensityResult banded = fit_intensities(index, surface, geometry, flat, {}, 1, 1);
    EXPECT_EQ(kept.target_pixels, static_cast<std::size_t>(cv::countNonZero(index.mask)));
    EXPECT_EQ(banded.target_pixels, kept.target_pixels);
    EXPECT_EQ(banded.pixels_used, kept.pixels_used);
    for (std::size_t i = 0; i < kept.relative.size(); ++i) {
      EXPECT_EQ(banded.relative[i], kept.relative[i]) << i;
      EXPECT_EQ(banded.residual[i], kept.residual[i]) << i;
      // Within 2.5 % at 128² (the lights from a 128² chrome sphere; at 256² within 1 %, above).
      EXPECT_NEAR(kept.relative[i], true_relative(rig, i), 0.025 * true_relative(rig, i)) << i;
    }
    ASSERT_EQ(kept.flat_field.empty(), !flat);
    if (flat) {
      EXPECT_EQ(cv::norm(kept.flat_field, banded.flat_field, cv::NORM_INF), 0.0);
    }
  }
  // A target outside the images is named.
  const TargetSurface nowhere =
      TargetSurface::plane(cv::Mat::zeros(index.image_size, CV_8UC1), cal.camera, 0);
  EXPECT_NE(error_of([&] {
              fit_intensities(index, nowhere, geometry, true, {});
            }).find("target: the intensity target covers no pixel"),
            std::string::npos);
}

// A Lambertian object about a fifth of the dome radius under near LEDs:
// solving with the calibrated LED positions beats the distant approximation.
TEST(CalibrationNearLights, NearLightLambertianLowersTheNormalError) {
  const Rig rig = load_rig(default_rig_path());
  const fs::path dir = testing::scratch_dir();
  write_sim_stack(rig, "chrome-probe", dir / "chrome", 256);
  write_sim_stack(rig, "matte-sphere", dir / "object", 256);
  LightCalibrationOptions o = chrome_sphere_options(dir / "chrome");
  const auto run = calibrate_lights(o);
  write_calibration_outputs(dir / "cal", run, o.inputs);

  L2Options l2;
  l2.shadow_threshold = 0.02;
  ImageStack stack = io::load_stack(dir / "object");
  const StackCalibration applied =
      apply_calibration_file(dir / "cal" / "calibration.json", dir / "object", stack);
  EXPECT_EQ(applied.matched_by, "led_id");
  Observations observations = make_observations(stack);
  const double distant = angular_error(solve_lambertian(observations, l2).normals,
                                       stack.ground_truth->normals, observations.mask)
                             .stats.mean;
  ASSERT_TRUE(set_near_lights(applied, observations));
  const double near = angular_error(solve_lambertian(observations, l2).normals, stack.ground_truth->normals,
                                    observations.mask)
                          .stats.mean;
  RecordProperty("distant_mean_deg", fmt::format("{:.3f}", distant));
  RecordProperty("near_mean_deg", fmt::format("{:.3f}", near));
  std::printf("near-light Lambertian: distant %.3f deg, near %.3f deg\n", distant, near);
  EXPECT_LT(near, 0.8 * distant);
}

// Uneven LEDs whose stack already records each one's brightness (the sim
// writes it into light_intensity): intensities calibrated from a matte sphere
// must replace the stack's, not multiply them (which counts the brightness
// twice), so the normals come out as with the true intensities.
TEST(CalibrationApply, CalibratedIntensitiesReplaceTheStacks) {
  const Rig rig = uneven_rig();
  const fs::path dir = testing::scratch_dir();
  write_sim_stack(rig, "chrome-probe", dir / "chrome", 256);
  write_sim_stack(rig, "matte-sphere", dir / "matte", 256);
  write_sim_stack(rig, "bunny", dir / "object", 256);
  LightCalibrationOptions o = chrome_sphere_options(dir / "chrome");
  o.intensity_input = dir / "matte";
  o.intensity_target = IntensityTarget::kMatteSphere;
  const auto run = calibrate_lights(o);
  write_calibration_outputs(dir / "cal", run, o.inputs);

  L2Options l2;
  l2.shadow_threshold = 0.02;
  auto solve = [&](bool true_intensities) {
    ImageStack stack = io::load_stack(dir / "object");
    std::vector<Vec3> truth;
    for (const Frame& frame : stack.frames) truth.push_back(frame.light_intensity);
    const StackCalibration applied =
        apply_calibration_file(dir / "cal" / "calibration.json", dir / "object", stack);
    EXPECT_TRUE(applied.intensities_replaced);
    if (true_intensities) {
      for (std::size_t f = 0; f < stack.frames.size(); ++f) stack.frames[f].light_intensity = truth[f];
    } else {
      // Calibrated relative intensities at the stack's own scale.
      double worst = 0;
      for (std::size_t f = 0; f < stack.frames.size(); ++f)
        worst = std::max(worst, std::abs(stack.frames[f].light_intensity.x() / truth[f].x() - 1));
      EXPECT_LT(worst, 0.02);
    }
    Observations observations = make_observations(stack);
    EXPECT_TRUE(set_near_lights(applied, observations));
    return angular_error(solve_lambertian(observations, l2).normals, stack.ground_truth->normals,
                         observations.mask)
        .stats.mean;
  };
  const double with_truth = solve(true), calibrated = solve(false);
  RecordProperty("true_intensities_mean_deg", fmt::format("{:.3f}", with_truth));
  RecordProperty("calibrated_intensities_mean_deg", fmt::format("{:.3f}", calibrated));
  std::printf("uneven LEDs: true intensities %.3f deg, calibrated %.3f deg\n", with_truth, calibrated);
  EXPECT_LT(calibrated, 1.1 * with_truth);
}

TEST(CalibrationApply, LpFileAndMismatchedStacks) {
  const Rig rig = load_rig(default_rig_path());
  const fs::path dir = testing::scratch_dir();
  write_sim_stack(rig, "chrome-probe", dir / "chrome", 128);
  LightCalibrationOptions o;
  o.inputs = {dir / "chrome"};
  const auto run = calibrate_lights(o);
  write_calibration_outputs(dir / "cal", run, o.inputs);
  for (const char* file : {"calibration.json", "light_directions.txt", "light_intensities.txt", "lights.lp",
                           "lights_hemisphere.png", "highlights.png"})
    EXPECT_TRUE(fs::exists(dir / "cal" / file)) << file;
  ImageStack stack = io::load_stack(dir / "chrome");
  const StackCalibration lp = apply_calibration_file(dir / "cal" / "lights.lp", dir / "chrome", stack);
  EXPECT_EQ(lp.matched_by, "filename");
  EXPECT_LT(angle_between_deg(stack.frames[10].light_direction, run.calibration.lights[10].direction), 1e-6);
  Observations observations = make_observations(stack);
  EXPECT_FALSE(set_near_lights(lp, observations));  // an .lp holds no positions
  // A stack with fewer frames and no LED ids cannot be matched by order.
  stack.frames.resize(10);
  for (auto& f : stack.frames) f.led_id = -1;
  const std::string message =
      error_of([&] { apply_calibration_file(dir / "cal" / "calibration.json", dir / "chrome", stack); });
  EXPECT_NE(message.find("96 lights, but the stack has 10 frames"), std::string::npos) << message;
}

}  // namespace
}  // namespace lightstage::calibration
