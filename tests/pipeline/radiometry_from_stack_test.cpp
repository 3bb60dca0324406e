// Radiometry a stack carries: solve linearises a gamma camera's frames with a
// response calibrated from an exposure bracket (as `camera response` does),
// and solves near lights from the manifest's LED positions without a flag.
#include "lightstage/common/error.hpp"
#include "lightstage/host/capture/response_curve.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/pipeline/simulate_folder.hpp"
#include "lightstage/pipeline/solve_folder.hpp"
#include "lightstage/testing/paths.hpp"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

namespace lightstage::pipeline {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;

fs::path rig_path() { return lightstage::testing::source_dir() / "hw/rigs/sim-dome.yaml"; }

sim::SimulateOptions bumps(const std::string& response, std::optional<double> exposure_us = {}) {
  sim::SimulateOptions o;
  o.scene = "bumps";
  o.width = 64;
  o.height = 64;
  o.sensor.noise = sim::NoiseModel::kNone;
  o.sensor.response = sim::ResponseCurve::parse(response);
  o.sensor.exposure_us = exposure_us;
  return o;
}

SolveSettings l2() {
  SolveSettings settings;
  settings.method = "l2";
  settings.threads = 2;
  settings.resolve();
  return settings;
}

// One frame of the gamma camera at every exposure of the default response bracket.
fs::path calibrated_gamma_response(const fs::path& dir) {
  const std::vector<double> exposures = response_bracket_us(10'000);
  std::vector<cv::Mat> images;
  for (std::size_t e = 0; e < exposures.size(); ++e) {
    const fs::path stack = dir / fmt::format("bracket{}", e);
    simulate_to_folder(rig_path(), bumps("gamma:2.2", exposures[e]), stack);
    images.push_back(io::load_stack(stack).frames.at(0).image);
  }
  const fs::path file = dir / "response.json";
  calibrate_response(images, exposures, 16).save(file);
  return file;
}

TEST(RadiometryFromStack, GammaCaptureWithItsCalibratedResponseSolvesAsLinear) {
  const fs::path dir = lightstage::testing::scratch_dir();
  simulate_to_folder(rig_path(), bumps("identity"), dir / "linear");
  simulate_to_folder(rig_path(), bumps("gamma:2.2"), dir / "gamma");
  const fs::path response = calibrated_gamma_response(dir);

  const double linear = solve_folder(dir / "linear", l2(), dir / "out_linear").error->mean;
  const double raw = solve_folder(dir / "gamma", l2(), dir / "out_raw").error->mean;
  SolveCalibration with_response;
  with_response.response = response;
  const SolveReport fixed = solve_folder(dir / "gamma", l2(), dir / "out_fixed", with_response);
  std::printf("gamma 2.2: linear %.3f deg, not linearised %.3f deg, calibrated response %.3f deg\n", linear,
              raw, fixed.error->mean);
  RecordProperty("linear_mean_deg", fmt::format("{:.3f}", linear));
  RecordProperty("gamma_raw_mean_deg", fmt::format("{:.3f}", raw));
  RecordProperty("gamma_calibrated_mean_deg", fmt::format("{:.3f}", fixed.error->mean));
  EXPECT_LE(fixed.error->mean, 1.2 * linear);
  EXPECT_GT(raw, 2 * linear);  // the fix matters on this stack
  EXPECT_EQ(fixed.summary["radiometry"]["response"]["source"], "file");
  EXPECT_EQ(fixed.summary["radiometry"]["response"]["applied"], true);
}

TEST(RadiometryFromStack, ResponseRecordedInTheManifestIsApplied) {
  const fs::path dir = lightstage::testing::scratch_dir();
  simulate_to_folder(rig_path(), bumps("identity"), dir / "linear");
  simulate_to_folder(rig_path(), bumps("gamma:2.2"), dir / "gamma");
  const fs::path response = calibrated_gamma_response(dir);
  {
    std::ifstream in(dir / "gamma/manifest.json");
    nlohmann::json manifest = nlohmann::json::parse(in);
    std::ifstream curve(response);
    manifest["radiometry"] = {
        {"linear", false}, {"response_applied", false}, {"response", nlohmann::json::parse(curve)}};
    std::ofstream(dir / "gamma/manifest.json") << manifest.dump(2);
  }
  const double linear = solve_folder(dir / "linear", l2(), dir / "out_linear").error->mean;
  const SolveReport fixed = solve_folder(dir / "gamma", l2(), dir / "out_fixed");
  EXPECT_LE(fixed.error->mean, 1.2 * linear);
  EXPECT_EQ(fixed.summary["radiometry"]["response"]["source"], "manifest");
}

TEST(RadiometryFromStack, BadResponseFileIsNamed) {
  const fs::path dir = lightstage::testing::scratch_dir();
  simulate_to_folder(rig_path(), bumps("gamma:2.2"), dir / "gamma");
  const fs::path bad = dir / "bad.json";
  std::ofstream(bad) << R"({"format": "lightstage-response", "version": 1, "bits": 16, "knots": "x"})";
  SolveCalibration with_response;
  with_response.response = bad;
  try {
    solve_folder(dir / "gamma", l2(), dir / "out", with_response);
    FAIL() << "a bad response file was accepted";
  } catch (const InputError& e) {
    EXPECT_THAT(std::string(e.what()), AllOf(HasSubstr(bad.string()), HasSubstr("knots")));
  }
}

TEST(RadiometryFromStack, LedPositionsInTheManifestGiveNearLights) {
  const fs::path dir = lightstage::testing::scratch_dir();
  simulate_to_folder(rig_path(), bumps("identity"), dir / "near");
  const SolveReport automatic = solve_folder(dir / "near", l2(), dir / "out_auto");
  SolveCalibration distant;
  distant.distant = true;
  const SolveReport reverted = solve_folder(dir / "near", l2(), dir / "out_distant", distant);
  std::printf("near-light stack: automatic %.3f deg, --distant-lights %.3f deg\n", automatic.error->mean,
              reverted.error->mean);
  RecordProperty("auto_near_mean_deg", fmt::format("{:.3f}", automatic.error->mean));
  RecordProperty("distant_mean_deg", fmt::format("{:.3f}", reverted.error->mean));
  EXPECT_EQ(automatic.summary["lights"]["model"], "near");
  EXPECT_EQ(automatic.summary["lights"]["source"], "stack");
  EXPECT_EQ(reverted.summary["lights"]["model"], "distant");
  EXPECT_LT(automatic.error->mean, 1.5);
  EXPECT_GT(reverted.error->mean, 3 * automatic.error->mean);
}

void set_manifest_radiometry(const fs::path& stack, const nlohmann::json& radiometry) {
  std::ifstream in(stack / "manifest.json");
  nlohmann::json manifest = nlohmann::json::parse(in);
  manifest["radiometry"] = radiometry;
  std::ofstream(stack / "manifest.json") << manifest.dump(2);
}

std::string solve_error(const fs::path& stack, const fs::path& out, const SolveCalibration& calibration) {
  try {
    solve_folder(stack, l2(), out, calibration);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(RadiometryFromStack, ManifestRadiometryErrorsNameTheField) {
  const fs::path dir = lightstage::testing::scratch_dir();
  simulate_to_folder(rig_path(), bumps("identity"), dir / "stack");
  const fs::path file = dir / "response.json";
  InverseResponse::identity(16).save(file);
  SolveCalibration with_response;
  with_response.response = file;
  set_manifest_radiometry(dir / "stack", {{"response_applied", true}});
  EXPECT_THAT(
      solve_error(dir / "stack", dir / "out1", with_response),
      AllOf(HasSubstr("manifest.json: radiometry.response_applied"), HasSubstr("without --response")));
  set_manifest_radiometry(dir / "stack", {{"linear", "yes"}});
  EXPECT_THAT(solve_error(dir / "stack", dir / "out2", {}),
              HasSubstr("manifest.json: radiometry.linear: expected true or false"));
}

}  // namespace
}  // namespace lightstage::pipeline
