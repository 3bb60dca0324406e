// `lightstage calibrate lights` and `solve --calibration` end to end: a
// simulated chrome-sphere stack on the default dome through the CLI, checked
// against the simulator's own light directions.
#include "lightstage/testing/paths.hpp"
#include "lightstage/testing/run.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>

namespace lightstage {
namespace {

using testing::run_lightstage;

nlohmann::json read_json(const std::filesystem::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

TEST(CalibrateCli, ChromeSphereToCalibrationToNearLightSolve) {
  const auto dir = testing::scratch_dir();
  auto run = run_lightstage(
      {"simulate", "--scene", "chrome-probe", "--width", "256", "--out", (dir / "chrome").string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  run = run_lightstage({"calibrate", "lights", "--input", (dir / "chrome").string(), "--rig", "default",
                        "--compare", (dir / "chrome").string(), "--out", (dir / "cal").string(), "--json"});
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
