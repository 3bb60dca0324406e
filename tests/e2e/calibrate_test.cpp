// `lightstage calibrate lights` and `solve --calibration` end to end: a
// simulated chrome-sphere stack on the default dome through the CLI, checked
// against the simulator's own light directions.
#include "lightstage/testing/paths.hpp"
#include "lightstage/testing/run.hpp"
#include "lightstage/testing/sanitizers.hpp"

#include <fmt/format.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <fstream>

namespace lightstage {
namespace {

using testing::run_lightstage;

nlohmann::json read_json(const std::filesystem::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

// The chrome probe simulated `side` pixels square into DIR/chrome, calibrated into DIR/cal against
// the simulator's lights: the calibration's run.
testing::RunResult calibrate_chrome_probe(const std::filesystem::path& dir, const std::string& side) {
  const auto simulated = run_lightstage({"simulate", "--quiet", "--scene", "chrome-probe", "--width", side,
                                         "--height", side, "--out", (dir / "chrome").string()});
  EXPECT_EQ(simulated.exit_code, 0) << simulated.err;
  return run_lightstage({"calibrate", "lights", "--input", (dir / "chrome").string(), "--rig", "default",
                         "--compare", (dir / "chrome").string(), "--out", (dir / "cal").string(), "--json"});
}

TEST(CalibrateCli, ChromeSphereToCalibrationToNearLightSolve) {
  const auto dir = testing::scratch_dir();
  auto run = calibrate_chrome_probe(dir, "256");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto summary = nlohmann::json::parse(run.out);
  EXPECT_EQ(summary["measured"], 96);
  EXPECT_EQ(summary["direction_method"], "dome-radius");
  EXPECT_LT(summary["comparison"]["mean_deg"].get<double>(), 0.1) << run.out;
  EXPECT_LT(summary["comparison"]["max_deg"].get<double>(), 0.3) << run.out;
  for (const char* file : {"calibration.json", "light_directions.txt", "light_intensities.txt", "lights.lp",
                           "lights_hemisphere.png", "highlights.png"})
    EXPECT_TRUE(std::filesystem::exists(dir / "cal" / file)) << file;
  const auto calibration = read_json(dir / "cal" / "calibration.json");
  EXPECT_EQ(calibration["format"], "lightstage-light-calibration");
  EXPECT_EQ(calibration["lights"].size(), 96u);

  run = run_lightstage(
      {"simulate", "--scene", "matte-sphere", "--width", "256", "--out", (dir / "object").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  run = run_lightstage({"solve", "--input", (dir / "object").string(), "--calibration",
                        (dir / "cal" / "calibration.json").string(), "--shadow-threshold", "0.02", "--out",
                        (dir / "result").string(), "--json"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto solved = nlohmann::json::parse(run.out);
  EXPECT_TRUE(solved.contains("calibration")) << run.out;
}

// Issue 18: a chrome-sphere stack is read a band of rows at a time for its median and brightest
// images, then each frame only around the sphere, one frame per thread: never the whole stack.
TEST(CalibrateCli, AChromeStackIsNeverHeldWhole) {
  LIGHTSTAGE_MEASURED_IN_RELEASE_ONLY("CalibrationImages (the views and regions equal the whole stack's)");
  const auto dir = testing::scratch_dir();
  // 96 frames of 1024x1024 with a sphere of 400 px radius: 503 MB as grey floats and clipping flags.
  const auto run = calibrate_chrome_probe(dir, "1024");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto summary = nlohmann::json::parse(run.out);
  EXPECT_EQ(summary["measured"], 96);
  EXPECT_LT(summary["comparison"]["mean_deg"].get<double>(), 0.1) << run.out;
  std::printf("calibrate lights, 96 x 1024x1024 chrome: peak %.0f MB\n", run.peak_rss_bytes / 1e6);
  RecordProperty("peak_rss_mb", fmt::format("{:.0f}", run.peak_rss_bytes / 1e6));
  EXPECT_LT(run.peak_rss_bytes, std::size_t{160} << 20);
}

TEST(CalibrateCli, BadInputNamesTheFolder) {
  const auto dir = testing::scratch_dir();
  std::filesystem::create_directories(dir / "empty");
  const auto run = run_lightstage(
      {"calibrate", "lights", "--input", (dir / "empty").string(), "--out", (dir / "cal").string()});
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.err.find("filenames.txt: no such file"), std::string::npos) << run.err;
}

}  // namespace
}  // namespace lightstage
