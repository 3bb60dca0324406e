// Capture through the three processes: lightstage-sim (gpiochip + camera),
// lightstage-domed and `lightstage capture`, then solve the stack.
#include "dome_fixture.hpp"

#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/host/radiometry.hpp"
#include "lightstage/testing/paths.hpp"
#include "lightstage/testing/run.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <csignal>
#include <fstream>
#include <set>
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

std::size_t frames_on_disk(const fs::path& dir, const std::string& extension = ".png") {
  std::size_t n = 0;
  if (!fs::exists(dir)) return 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    const bool numbered_frame =
        name.size() == 7 && name.ends_with(extension) &&
        std::all_of(name.begin(), name.begin() + 3, [](unsigned char c) { return std::isdigit(c); });
    if (numbered_frame) ++n;
  }
  return n;
}

// Waits until no file has come into `dir` for `quiet` (or ten seconds have passed).
void wait_until_quiet(const fs::path& dir, std::chrono::milliseconds quiet) {
  const auto count = [&] {
    return static_cast<std::size_t>(std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
  };
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  auto last_change = std::chrono::steady_clock::now();
  std::size_t files = count();
  while (std::chrono::steady_clock::now() - last_change < quiet &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(milliseconds(20));
    if (const std::size_t now = count(); now != files) {
      files = now;
      last_change = std::chrono::steady_clock::now();
    }
  }
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

// A DSLR on the remote port (lightstage-sim's simulated one: random shutter
// lag and card delay, DNG files in a folder): every file filed under its own
// LED, a lost file retaken, and a killed host resumed to the same stack.
TEST(CaptureIntegration, DslrFilesFindTheirLedsAndAKilledHostResumes) {
  const fs::path shots = scratch_dir() / "shots";
  fs::create_directories(shots);
  std::vector<std::string> sim_args = kScene;
  for (const std::string& a : {std::string("--dslr"), shots.string(), std::string("--dslr-exposure-us"),
                               std::string("4000"), std::string("--dslr-drop"), std::string("9")})
    sim_args.push_back(a);
  SimulatedDome dome({source_dir() / "hw/rigs/sim-dome-dslr.yaml", sim_args, {}, false});
  const auto args = [&](const fs::path& out) {
    std::vector<std::string> a = capture_args(dome, out);
    a[6] = "folder:" + shots.string() + "?poll_ms=10";  // --camera
    a.insert(a.end(), {"--leds", "0,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,19,20,21,22,23", "--json"});
    return a;
  };
  const auto whole = scratch_dir() / "whole";
  const RunResult first = run_lightstage(args(whole));
  ASSERT_EQ(first.exit_code, 0) << first.err << dome.logs();
  EXPECT_GE(nlohmann::json::parse(first.out).at("retakes").get<int>(), 1) << "shot 9 never arrived";

  const auto cut = scratch_dir() / "cut";
  {
    ChildProcess host(bin_dir() / "lightstage", args(cut), scratch_dir() / "host.log");
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (frames_on_disk(cut) < 8 && std::chrono::steady_clock::now() < deadline && host.running()) {
      std::this_thread::sleep_for(milliseconds(5));
    }
    host.signal(SIGKILL);
    host.wait(std::chrono::seconds(5));
  }
  // A shot the killed host had pressed still lands, up to the card delay later (0.9 s at most): an
  // operator's restart takes longer, and the resumed host ignores files already there. Resumed within
  // milliseconds, the host could take that file for its first batch's.
  wait_until_quiet(shots, milliseconds(1500));
  const std::size_t kept = frames_on_disk(cut);
  ASSERT_GE(kept, 8u);
  ASSERT_LT(kept, 24u) << "the capture finished before it could be interrupted";
  std::vector<std::string> resume = args(cut);
  resume.push_back("--resume");
  const RunResult resumed = run_lightstage(resume);
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err << dome.logs();

  // Noise-free: a file filed under another LED would differ from the uninterrupted capture.
  const ImageStack a = io::load_stack(whole), b = io::load_stack(cut);
  ASSERT_EQ(a.frames.size(), 24u);
  ASSERT_EQ(b.frames.size(), 24u);
  for (std::size_t i = 0; i < a.frames.size(); ++i) {
    EXPECT_EQ(b.frames[i].led_id, static_cast<int>(i));
    EXPECT_EQ(a.frames[i].image.type(), CV_16UC3);
    EXPECT_LE(cv::norm(a.frames[i].image, b.frames[i].image, cv::NORM_INF), 1) << "frame " << i;
  }
  // Each frame names its own original, which is still where it arrived.
  std::ifstream manifest_file(cut / "manifest.json");
  const auto manifest = nlohmann::json::parse(manifest_file);
  std::set<std::string> originals;
  for (const auto& frame : manifest.at("frames")) {
    const std::string original = frame.at("source_image").get<std::string>();
    EXPECT_TRUE(fs::exists(original)) << original;
    originals.insert(original);
  }
  EXPECT_EQ(originals.size(), 24u);
}

// A DSLR whose dial is at another shutter speed than the capture asks: refused
// naming both, not mixed into the stack.
TEST(CaptureIntegration, ADslrSetToAnotherShutterSpeedIsRefusedNamingBoth) {
  const fs::path shots = scratch_dir() / "shots";
  fs::create_directories(shots);
  std::vector<std::string> sim_args = kScene;
  for (const std::string& a :
       {std::string("--dslr"), shots.string(), std::string("--dslr-exposure-us"), std::string("16667")})
    sim_args.push_back(a);
  SimulatedDome dome({source_dir() / "hw/rigs/sim-dome-dslr.yaml", sim_args, {}, false});
  std::vector<std::string> args = capture_args(dome, scratch_dir() / "capture");
  args[6] = "folder:" + shots.string();  // --camera
  args.insert(args.end(), {"--leds", "0,1"});
  const RunResult capture = run_lightstage(args);
  EXPECT_NE(capture.exit_code, 0);
  EXPECT_NE(capture.err.find("was exposed 1/60 s but the capture asked 1/250 s"), std::string::npos)
      << capture.err;
  EXPECT_NE(capture.err.find("--resume"), std::string::npos) << capture.err;
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

// A shiny sphere: its highlights are ~200 times the diffuse shading.
const std::vector<std::string> kShinyScene = {
    "--scene",       "shiny-sphere", "--material", "blinn-phong:shininess=200,ks=0.8",
    "--lights",      "distant",      "--width",    "64",
    "--height",      "64",           "--noise",    "none",
    "--black-level", "512"};

nlohmann::json read_manifest(const fs::path& stack) {
  std::ifstream in(stack / "manifest.json");
  return nlohmann::json::parse(in);
}

// Every LED bracketed at 16, 4 and 1 ms: 16 ms clips the highlights, 1 ms
// still clips their peaks. The merge must be linear — equal to a single
// capture divided by its exposure wherever that capture is well inside its
// range, highlights clipped at 16 ms included — and must flag the peaks.
TEST(CaptureIntegration, HdrBracketsMergeLinearlyAndFlagPixelsClippedAtEveryExposure) {
  SimulatedDome dome({{}, kShinyScene, {}, true});
  const std::string leds = "0,30,41,60,90";
  const auto capture = [&](const fs::path& out, const std::string& exposure, std::vector<std::string> more) {
    std::vector<std::string> args = capture_args(dome, out);
    args[10] = exposure;  // --exposure-us
    args.insert(args.end(), {"--leds", leds, "--json"});
    args.insert(args.end(), more.begin(), more.end());
    const RunResult run = run_lightstage(args);
    EXPECT_EQ(run.exit_code, 0) << run.err << dome.logs();
    return run.exit_code == 0 ? nlohmann::json::parse(run.out) : nlohmann::json();
  };
  const auto hdr = scratch_dir() / "hdr";
  const auto report = capture(hdr, "16000", {"--bracket", "0,-2,-4"});
  ASSERT_FALSE(report.is_null());
  EXPECT_EQ(report.at("frames").get<int>(), 5);
  EXPECT_EQ(report.at("bracket_frames").get<int>(), 15);
  // References: single noise-free captures, one short (the highlights in
  // range) and one as long as the bracket's longest (the diffuse well exposed).
  const auto short_ref = scratch_dir() / "short", long_ref = scratch_dir() / "long";
  ASSERT_FALSE(capture(short_ref, "250", {}).is_null());
  ASSERT_FALSE(capture(long_ref, "16000", {}).is_null());

  const ImageStack merged = io::load_stack(hdr), a = io::load_stack(short_ref), b = io::load_stack(long_ref);
  ASSERT_EQ(merged.frames.size(), 5u);
  const auto manifest = read_manifest(hdr);
  EXPECT_EQ(manifest.at("capture").at("bracket_stops"), nlohmann::json({0.0, -2.0, -4.0}));
  const double clip = 0.98 * 65535;
  std::size_t compared = 0, rescued = 0, flagged = 0;
  double worst = 0, sum = 0;
  for (std::size_t i = 0; i < merged.frames.size(); ++i) {
    const Frame& m = merged.frames[i];
    ASSERT_EQ(m.image.type(), CV_32FC1) << m.filename;
    EXPECT_EQ(m.filename, fmt::format("{:03}.pfm", i + 1));
    EXPECT_TRUE(m.dark.empty()) << "merged frames are dark-subtracted already";
    EXPECT_EQ(m.exposure_us, 1e6);
    EXPECT_FLOAT_EQ(static_cast<float>(m.saturation_level), static_cast<float>(1 / 1000e-6));
    const auto& entry = manifest.at("frames").at(i);
    EXPECT_EQ(entry.at("bracket_exposures_us"), nlohmann::json({1000.0, 4000.0, 16000.0}));
    EXPECT_GT(entry.at("bracket").at(2).at("clipped_values").get<int>(), 0)
        << "16 ms must clip the highlight";
    // Single captures name their exposure's dark, subtracted pixel by pixel.
    ASSERT_EQ(a.frames[i].dark_file, "dark_250us.png");
    ASSERT_FALSE(a.frames[i].dark.empty());
    for (int y = 0; y < m.image.rows; ++y) {
      for (int x = 0; x < m.image.cols; ++x) {
        const double value = m.image.at<float>(y, x);
        const double short_dn =
            a.frames[i].image.at<std::uint16_t>(y, x) - a.frames[i].dark.at<std::uint16_t>(y, x);
        const double long_raw = b.frames[i].image.at<std::uint16_t>(y, x);
        const double long_dn = long_raw - b.frames[i].dark.at<std::uint16_t>(y, x);
        // What the shortest bracket exposure (1 ms) recorded, predicted from the 250 us reference.
        const double at_shortest = 512 + short_dn * 4;
        if (value >= m.saturation_level) {
          ++flagged;
          EXPECT_GT(at_shortest, 0.97 * 65535)
              << "flagged but in range at 1 ms: " << i << " " << x << "," << y;
          continue;
        }
        EXPECT_LT(at_shortest, 0.99 * 65535)
            << "clipped at every exposure but not flagged: " << x << "," << y;
        double reference = 0;
        if (long_raw < clip && long_dn >= 200) {
          reference = long_dn / 65535 / 16000e-6;
        } else if (short_dn >= 200) {
          reference = short_dn / 65535 / 250e-6;
          if (long_raw >= clip) ++rescued;
        } else {
          continue;
        }
        const double error = std::abs(value / reference - 1);
        worst = std::max(worst, error);
        sum += error;
        ++compared;
      }
    }
  }
  ASSERT_GT(compared, 1000u);
  EXPECT_GT(rescued, 20u) << "highlights clipped at 16 ms, in range after the merge";
  EXPECT_GT(flagged, 5u) << "peaks clipped even at 1 ms";
  EXPECT_LT(worst, 0.02);
  RecordProperty("hdr_worst_relative_error", std::to_string(worst));
  RecordProperty("hdr_mean_relative_error", std::to_string(sum / static_cast<double>(compared)));
  RecordProperty("hdr_pixels_compared", std::to_string(compared));
  RecordProperty("hdr_highlight_pixels_rescued", std::to_string(rescued));
  RecordProperty("hdr_pixels_flagged", std::to_string(flagged));

  // The flags reach the solvers: radiometry marks exactly those observations saturated.
  const Observations obs = make_observations(merged);
  std::size_t saturated = 0;
  for (Eigen::Index p = 0; p < obs.saturated.rows(); ++p) {
    for (Eigen::Index j = 0; j < obs.saturated.cols(); ++j) saturated += obs.saturated(p, j) ? 1 : 0;
  }
  EXPECT_EQ(saturated, flagged);
}

// An interrupted HDR capture keeps its merged frames; --resume takes only the
// LEDs not merged yet and ends with the stack an uninterrupted run gives.
TEST(CaptureIntegration, KilledHdrCaptureResumesWithoutRetakingFinishedLeds) {
  SimulatedDome dome({{}, kScene, {}, true});
  std::string leds;
  for (int i = 0; i < 36; ++i) leds += (i ? "," : "") + std::to_string(i);
  const auto args = [&](const fs::path& out) {
    std::vector<std::string> a = capture_args(dome, out);
    a.insert(a.end(), {"--leds", leds, "--bracket", "0,-2"});
    return a;
  };
  const auto whole = scratch_dir() / "whole";
  ASSERT_EQ(run_lightstage(args(whole)).exit_code, 0) << dome.logs();

  const auto cut = scratch_dir() / "cut";
  {
    ChildProcess host(bin_dir() / "lightstage", args(cut), scratch_dir() / "host.log");
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (frames_on_disk(cut, ".pfm") < 12 && std::chrono::steady_clock::now() < deadline &&
           host.running()) {
      std::this_thread::sleep_for(milliseconds(5));
    }
    host.signal(SIGKILL);
    host.wait(std::chrono::seconds(5));
  }
  const std::size_t kept = frames_on_disk(cut, ".pfm");
  ASSERT_GE(kept, 12u);
  ASSERT_LT(kept, 36u) << "the capture finished before it could be interrupted";
  const std::size_t done = read_manifest(cut).at("capture").at("done").size();
  EXPECT_GE(done, kept - 1);

  std::vector<std::string> resume = args(cut);
  resume.insert(resume.end(), {"--resume", "--json"});
  const RunResult resumed = run_lightstage(resume);
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err << dome.logs();
  const auto report = nlohmann::json::parse(resumed.out);
  EXPECT_EQ(report.at("taken_now").get<std::size_t>(), 36 - done) << "finished LEDs are not taken again";
  EXPECT_EQ(report.at("bracket_frames").get<std::size_t>(), 2 * (36 - done));
  // Another bracket than the one planned is refused.
  std::vector<std::string> other = capture_args(dome, cut);
  other.insert(other.end(), {"--leds", leds, "--bracket", "0,-3", "--resume"});
  EXPECT_NE(run_lightstage(other).exit_code, 0);

  const ImageStack x = io::load_stack(whole), y = io::load_stack(cut);
  ASSERT_EQ(x.frames.size(), 36u);
  ASSERT_EQ(y.frames.size(), 36u);
  for (std::size_t i = 0; i < x.frames.size(); ++i) {
    EXPECT_EQ(x.frames[i].led_id, y.frames[i].led_id);
    EXPECT_EQ(cv::norm(x.frames[i].image, y.frames[i].image, cv::NORM_INF), 0) << "frame " << i;
  }
}

}  // namespace
}  // namespace lightstage::testing
