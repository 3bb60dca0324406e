// Capture through the three processes: lightstage-sim (gpiochip + camera),
// lightstage-domed and `lightstage capture`, then solve the stack.
#include "dome_fixture.hpp"

#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/testing/paths.hpp"
#include "lightstage/testing/run.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <csignal>
#include <fstream>
#include <thread>

namespace lightstage::testing {
namespace {

namespace fs = std::filesystem;
using std::chrono::milliseconds;

const std::vector<std::string> kScene = {"--scene", "sphere",   "--lights", "distant", "--width",
                                         "64",      "--height", "64",       "--noise", "none"};

std::vector<std::string> capture_args(const SimulatedDome& dome, const fs::path& out) {
  return {"capture",
          "--rig",
          dome.rig().string(),
          "--controller",
          dome.controller_uri(),
          "--camera",
          dome.camera_uri(),
          "--out",
          out.string(),
          "--exposure-us",
          "4000",
          "--dark-frames",
          "2",
          "--quiet"};
}

std::size_t frames_on_disk(const fs::path& dir) {
  std::size_t n = 0;
  if (!fs::exists(dir)) return 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    const bool numbered_frame = name.size() == 7 && name.ends_with(".png") &&
                                std::all_of(name.begin(), name.begin() + 3, [](unsigned char c) { return std::isdigit(c); });
    if (numbered_frame) ++n;
  }
  return n;
}

double mean_error_against_truth(const fs::path& stack, const fs::path& scratch) {
  // The same scene rendered directly gives the ground truth and mask of the captured view.
  const auto truth = scratch / "truth";
  const RunResult sim = run_lightstage({"simulate", "--scene", "sphere", "--lights", "distant", "--width",
                                        "64", "--height", "64", "--noise", "none", "--out", truth.string()});
  EXPECT_EQ(sim.exit_code, 0) << sim.err;
  fs::copy_file(truth / "mask.png", stack / "mask.png", fs::copy_options::overwrite_existing);
  const auto result = scratch / "result";
  const RunResult solve = run_lightstage({"solve", "--input", stack.string(), "--method", "l2",
                                          "--shadow-threshold", "0.02", "--out", result.string()});
  EXPECT_EQ(solve.exit_code, 0) << solve.err;
  const RunResult eval =
      run_lightstage({"eval", "--pred", (result / "normal.png").string(), "--gt", truth.string(), "--json"});
  EXPECT_EQ(eval.exit_code, 0) << eval.err;
  return nlohmann::json::parse(eval.out).at("mean_deg").get<double>();
}

TEST(CaptureIntegration, LambertianSphereCapturedAndSolvedUnderOneDegree) {
  SimulatedDome dome({{}, kScene, {}, true});
  const auto out = scratch_dir() / "capture";
  const RunResult capture = run_lightstage(capture_args(dome, out));
  ASSERT_EQ(capture.exit_code, 0) << capture.err << dome.logs();
  const ImageStack stack = io::load_stack(out);
  ASSERT_EQ(stack.frames.size(), 96u);
  for (std::size_t i = 0; i < stack.frames.size(); ++i) {
    EXPECT_EQ(stack.frames[i].led_id, static_cast<int>(i)) << "frame " << i << " is not its LED's";
    EXPECT_DOUBLE_EQ(stack.frames[i].exposure_us, 4000);
  }
  std::ifstream manifest_file(out / "manifest.json");
  const auto manifest = nlohmann::json::parse(manifest_file);
  EXPECT_TRUE(manifest.at("capture").at("complete").get<bool>());
  EXPECT_EQ(manifest.at("capture").at("loop"), "closed");
  const double error = mean_error_against_truth(out, scratch_dir());
  EXPECT_LT(error, 1.0) << "mean angular error of the captured stack";
  RecordProperty("mean_error_deg", std::to_string(error));
}

TEST(CaptureIntegration, ADroppedFrameIsRetaken) {
  std::vector<std::string> sim_args = kScene;
  for (const char* a : {"--camera-fault", "drop-frame:10"}) sim_args.emplace_back(a);
  SimulatedDome dome({{}, sim_args, {}, true});
  const auto out = scratch_dir() / "capture";
  std::vector<std::string> args = capture_args(dome, out);
  args.insert(args.end(), {"--leds", "0,1,2,3,4,5,6,7,8,9,10,11", "--json"});
  const RunResult capture = run_lightstage(args);
  ASSERT_EQ(capture.exit_code, 0) << capture.err << dome.logs();
  const auto report = nlohmann::json::parse(capture.out);
  EXPECT_EQ(report.at("frames").get<int>(), 12);
  EXPECT_GE(report.at("retakes").get<int>(), 1) << capture.out;
  const ImageStack stack = io::load_stack(out);
  ASSERT_EQ(stack.frames.size(), 12u);
  for (std::size_t i = 0; i < 12; ++i) EXPECT_EQ(stack.frames[i].led_id, static_cast<int>(i));
}

// An interrupted capture keeps its frames, and --resume completes it with the
// same content as an uninterrupted one (noise-free sim: bit for bit).
TEST(CaptureIntegration, KilledHostResumesToTheSameStack) {
  SimulatedDome dome({{}, kScene, {}, true});
  const auto whole = scratch_dir() / "whole";
  ASSERT_EQ(run_lightstage(capture_args(dome, whole)).exit_code, 0) << dome.logs();

  const auto cut = scratch_dir() / "cut";
  {
    ChildProcess host(bin_dir() / "lightstage", capture_args(dome, cut), scratch_dir() / "host.log");
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (frames_on_disk(cut) < 30 && std::chrono::steady_clock::now() < deadline && host.running()) {
      std::this_thread::sleep_for(milliseconds(5));
    }
    host.signal(SIGKILL);
    host.wait(std::chrono::seconds(5));
  }
  const std::size_t kept = frames_on_disk(cut);
  ASSERT_GE(kept, 30u);
  ASSERT_LT(kept, 96u) << "the capture finished before it could be interrupted";
  // What was taken is on disk and listed in the manifest (the frame in flight may not be).
  std::ifstream manifest_file(cut / "manifest.json");
  const auto manifest = nlohmann::json::parse(manifest_file);
  EXPECT_GE(manifest.at("capture").at("done").size(), kept - 1);
  EXPECT_FALSE(manifest.at("capture").at("complete").get<bool>());
  // Without --resume the folder is refused, not overwritten.
  EXPECT_NE(run_lightstage(capture_args(dome, cut)).exit_code, 0);

  std::vector<std::string> resume = capture_args(dome, cut);
  resume.push_back("--resume");
  const RunResult resumed = run_lightstage(resume);
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err << dome.logs();
  const ImageStack a = io::load_stack(whole), b = io::load_stack(cut);
  ASSERT_EQ(a.frames.size(), b.frames.size());
  for (std::size_t i = 0; i < a.frames.size(); ++i) {
    EXPECT_EQ(a.frames[i].led_id, b.frames[i].led_id);
    EXPECT_EQ(a.frames[i].filename, b.frames[i].filename);
    EXPECT_EQ(cv::norm(a.frames[i].image, b.frames[i].image, cv::NORM_INF), 0) << "frame " << i;
  }
}

TEST(CaptureIntegration, AVanishedControllerLeavesTheDomeDarkAndTheCaptureResumable) {
  SimulatedDome dome({{}, kScene, {}, true});
  const auto out = scratch_dir() / "capture";
  {
    ChildProcess host(bin_dir() / "lightstage", capture_args(dome, out), scratch_dir() / "host.log");
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (frames_on_disk(out) < 20 && std::chrono::steady_clock::now() < deadline && host.running()) {
      std::this_thread::sleep_for(milliseconds(5));
    }
    dome.firmware().signal(SIGKILL);
    const auto code = host.wait(std::chrono::seconds(20));
    ASSERT_TRUE(code.has_value()) << "the host hangs when the controller vanishes";
    EXPECT_NE(*code, 0);
    EXPECT_NE(host.output().find("the frames taken so far are kept"), std::string::npos) << host.output();
  }
  std::this_thread::sleep_for(milliseconds(300));
  EXPECT_TRUE(dome.read_timeline().leds_left_on().empty()) << "LEDs lit after the controller died";
  const std::size_t kept = frames_on_disk(out);
  EXPECT_GE(kept, 20u);
  dome.restart_firmware();
  std::vector<std::string> resume = capture_args(dome, out);
  resume.push_back("--resume");
  const RunResult resumed = run_lightstage(resume);
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err << dome.logs();
  EXPECT_EQ(io::load_stack(out).frames.size(), 96u);
}

// A camera with a tone curve: after calibrating its response from a bracket,
// its data is linear within 1%; before, it is far from it.
TEST(CaptureIntegration, ANonlinearCameraIsLinearAfterResponseCalibration) {
  std::vector<std::string> sim_args = kScene;
  for (const char* a : {"--response", "gamma:2.2"}) sim_args.emplace_back(a);
  SimulatedDome dome({{}, sim_args, {}, true});
  const std::vector<std::string> dome_args = {
      "--rig",    dome.rig().string(), "--controller", dome.controller_uri(),
      "--camera", dome.camera_uri(),   "--led",        "40"};
  // Linearity is checked where many pixels are well exposed in every frame;
  // the response is fitted over a wider bracket.
  std::vector<std::string> bracket = dome_args, wide = dome_args;
  bracket.insert(bracket.end(), {"--exposures-us", "5000,7000,10000"});
  wide.insert(wide.end(), {"--exposures-us", "1000,2000,4000,8000,16000,32000"});
  std::vector<std::string> raw = {"camera", "linearity", "--json"};
  raw.insert(raw.end(), bracket.begin(), bracket.end());
  const RunResult before = run_lightstage(raw);
  ASSERT_EQ(before.exit_code, 0) << before.err << dome.logs();
  EXPECT_GT(nlohmann::json::parse(before.out).at("max_deviation").get<double>(), 0.1);

  const auto response = scratch_dir() / "response.json";
  std::vector<std::string> calibrate = {"camera", "response", "--out", response.string()};
  calibrate.insert(calibrate.end(), wide.begin(), wide.end());
  const RunResult fit = run_lightstage(calibrate);
  ASSERT_EQ(fit.exit_code, 0) << fit.err << dome.logs();

  std::vector<std::string> checked = {"camera", "linearity", "--json", "--response", response.string()};
  checked.insert(checked.end(), bracket.begin(), bracket.end());
  const RunResult after = run_lightstage(checked);
  ASSERT_EQ(after.exit_code, 0) << after.err;
  const double deviation = nlohmann::json::parse(after.out).at("max_deviation").get<double>();
  EXPECT_LT(deviation, 0.01) << after.out;
  RecordProperty("linearity_after_calibration", std::to_string(deviation));
}

}  // namespace
}  // namespace lightstage::testing
