// `lightstage demo`, the README's main command: three processes (lightstage,
// lightstage-sim, lightstage-domed), chrome-sphere calibration, capture,
// solve, surface and report — measured against the simulator's truth.
#include "lightstage/common/child_process.hpp"
#include "lightstage/testing/paths.hpp"
#include "lightstage/testing/run.hpp"
#include "lightstage/testing/sanitizers.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <csignal>
#include <fstream>
#include <sstream>
#include <thread>

#include <unistd.h>

namespace lightstage::testing {
namespace {

namespace fs = std::filesystem;

// Processes whose command line mentions `text` (our children carry the rig path).
std::vector<std::string> processes_mentioning(const std::string& text) {
  std::vector<std::string> found;
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string pid = entry.path().filename().string();
    if (pid.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream in(entry.path() / "cmdline");
    std::stringstream cmdline;
    cmdline << in.rdbuf();
    std::string text_args = cmdline.str();
    for (char& c : text_args) {
      if (c == '\0') c = ' ';
    }
    if (text_args.find(text) != std::string::npos) found.push_back(pid + ": " + text_args);
  }
  return found;
}

// A copy of the default rig at a path unique to the test, to find its programs by.
fs::path unique_rig(const fs::path& dir) {
  // Named by our pid too: an earlier aborted run's programs must not count.
  const fs::path rig = dir / ("demo-rig-" + std::to_string(::getpid()) + ".yaml");
  fs::copy_file(source_dir() / "hw/rigs/sim-dome.yaml", rig, fs::copy_options::overwrite_existing);
  return rig;
}

TEST(DemoIntegration, CalibratesCapturesSolvesAndReportsThroughThreeProcesses) {
  const fs::path dir = scratch_dir();
  const fs::path out = dir / "demo";
  const fs::path rig = unique_rig(dir);
  const RunResult run = run_lightstage({"demo", "--rig", rig.string(), "--scene", "sphere", "--width", "128",
                                        "--height", "128", "--out", out.string(), "--json"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto summary = nlohmann::json::parse(run.out);

  // Every stage captured all 96 LEDs through the firmware.
  for (const char* stage : {"chrome-1", "chrome-2", "object"}) {
    ASSERT_TRUE(summary["captures"].contains(stage)) << run.out;
    EXPECT_EQ(summary["captures"][stage]["frames"].get<int>(), 96) << stage;
  }
  // The calibration found the simulator's LEDs from the captured chrome spheres.
  const auto& calibration = summary["calibration"];
  EXPECT_EQ(calibration["measured"].get<int>(), 96);
  EXPECT_LT(calibration["direction_error_deg"]["mean"].get<double>(), 0.5) << calibration.dump();
  EXPECT_LT(calibration["position_error_mm"]["mean"].get<double>(), 12.0) << calibration.dump();
  RecordProperty("calibration_direction_mean_deg",
                 std::to_string(calibration["direction_error_deg"]["mean"].get<double>()));
  // Normals from the captured stack with the calibrated near lights.
  const double mean_error = summary["solve"]["error_vs_ground_truth"]["mean_deg"].get<double>();
  RecordProperty("normal_mean_error_deg", std::to_string(mean_error));
  EXPECT_LT(mean_error, 1.5) << summary.dump();

  for (const fs::path& file :
       {fs::path("calibration/calibration.json"), fs::path("capture/Normal_gt.png"),
        fs::path("capture/mask.png"), fs::path("result/normal.png"), fs::path("result/report.html"),
        fs::path("surface/depth.pfm"), fs::path("surface/mesh.ply"), fs::path("demo.json")}) {
    EXPECT_TRUE(fs::exists(out / file)) << file;
  }
  std::ifstream page(out / "result/report.html");
  std::stringstream html;
  html << page.rdbuf();
  EXPECT_NE(html.str().find("depth"), std::string::npos) << "the report shows the integrated surface";
  EXPECT_TRUE(processes_mentioning(rig.string()).empty()) << "the dome's programs outlive the demo";
}

// `lightstage demo --camera dslr`: the same pipeline with lightstage-sim's DSLR
// on the remote port (random shutter lag, card delays, lost files), its DNGs
// taken from a folder, normals within 1.2x the sim: camera's error.
TEST(DemoIntegration, ADslrOnTheRemotePortSolvesAsWellAsTheSimCamera) {
  LIGHTSTAGE_MEASURED_IN_RELEASE_ONLY("CaptureIntegration.DslrFilesFindTheirLedsAndAKilledHostResumes");
  const fs::path dir = scratch_dir();
  const auto demo = [&](const std::string& camera, const fs::path& rig) {
    const RunResult run = run_lightstage({"demo", "--camera", camera, "--rig", rig.string(), "--scene",
                                          "sphere", "--width", "128", "--height", "128", "--dslr-drop-rate",
                                          "0.03", "--out", (dir / camera).string(), "--json"});
    EXPECT_EQ(run.exit_code, 0) << run.err;
    return run.exit_code == 0 ? nlohmann::json::parse(run.out) : nlohmann::json();
  };
  const auto sim = demo("sim", source_dir() / "hw/rigs/sim-dome.yaml");
  const auto dslr = demo("dslr", source_dir() / "hw/rigs/sim-dome-dslr.yaml");
  ASSERT_FALSE(sim.empty() || dslr.empty());
  EXPECT_EQ(dslr["camera"], "dslr");
  int retaken = 0;
  for (const char* stage : {"chrome-1", "chrome-2", "object"}) {
    EXPECT_EQ(dslr["captures"][stage]["frames"].get<int>(), 96) << stage;
    retaken += dslr["captures"][stage]["retakes"].get<int>();
  }
  EXPECT_GE(retaken, 1) << "3 % of about 300 shots are lost and must be retaken";
  const double sim_error = sim["solve"]["error_vs_ground_truth"]["mean_deg"].get<double>();
  const double dslr_error = dslr["solve"]["error_vs_ground_truth"]["mean_deg"].get<double>();
  RecordProperty("sim_camera_mean_error_deg", std::to_string(sim_error));
  RecordProperty("dslr_mean_error_deg", std::to_string(dslr_error));
  EXPECT_LE(dslr_error, 1.2 * sim_error)
      << "DSLR " << dslr_error << " deg, sim: camera " << sim_error << " deg";
  // The object's frames are the DSLR's files, each kept where it arrived.
  std::ifstream manifest_file(dir / "dslr/capture/manifest.json");
  const auto manifest = nlohmann::json::parse(manifest_file);
  for (const auto& frame : manifest.at("frames")) {
    const fs::path original = frame.at("source_image").get<std::string>();
    EXPECT_EQ(original.parent_path(), dir / "dslr/shots/object");
    EXPECT_TRUE(fs::exists(original)) << original;
  }
}

TEST(DemoIntegration, AKilledDemoTakesItsDomeWithIt) {
  const fs::path dir = scratch_dir();
  const fs::path rig = unique_rig(dir);
  ChildProcess demo(bin_dir() / "lightstage",
                    {"demo", "--rig", rig.string(), "--scene", "sphere", "--width", "64", "--height", "64",
                     "--out", (dir / "demo").string()},
                    dir / "demo.log");
  // Wait until the dome runs (the first capture is under way).
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  std::vector<std::string> seen = processes_mentioning(rig.string());
  while (seen.size() < 3 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    seen = processes_mentioning(rig.string());
  }
  ASSERT_GE(seen.size(), 3u) << demo.output();
  demo.signal(SIGKILL);
  ASSERT_TRUE(demo.wait(std::chrono::seconds(10)).has_value());
  // The children were told (parent-death signal) and stop; the dome goes dark on its way out.
  const auto gone_by = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (!processes_mentioning(rig.string()).empty() && std::chrono::steady_clock::now() < gone_by) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const auto left = processes_mentioning(rig.string());
  EXPECT_TRUE(left.empty()) << left.front();
}

TEST(DemoIntegration, MissingProgramsAreNamed) {
  const fs::path dir = scratch_dir();
  const RunResult run = run_lightstage({"demo", "--programs", (dir / "nowhere").string(), "--width", "32",
                                        "--height", "32", "--out", (dir / "demo").string()});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("lightstage-sim not found in"), std::string::npos) << run.err;
}

}  // namespace
}  // namespace lightstage::testing
