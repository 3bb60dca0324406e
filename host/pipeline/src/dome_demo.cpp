#include "lightstage/pipeline/dome_demo.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/common/rig.hpp"
#include "lightstage/host/calibration/calibrate_lights.hpp"
#include "lightstage/host/calibration/calibration_output.hpp"
#include "lightstage/host/capture/file_camera.hpp"
#include "lightstage/host/controller/controller_client.hpp"
#include "lightstage/host/demo/simulated_dome.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/normal_map.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/io/solve_output.hpp"
#include "lightstage/host/report/report.hpp"
#include "lightstage/host/surface/integration.hpp"
#include "lightstage/host/surface/surface_output.hpp"
#include "lightstage/pipeline/socket_folder.hpp"
#include "lightstage/pipeline/solve_folder.hpp"
#include "lightstage/sim/camera/sim_camera.hpp"
#include "lightstage/sim/simulate.hpp"

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include <chrono>
#include <cstdlib>
#include <fstream>

namespace lightstage::pipeline {
namespace {

namespace fs = std::filesystem;

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

struct Stage {
  std::string name;      // "chrome-1", "object": the log folder's and the socket folder's name
  std::string scene;     // lightstage-sim --scene
  std::string material;  // lightstage-sim --material ("" = the scene's)
  fs::path stack;        // where the capture goes
  // A mirror sphere: its highlight is a few pixels, too few for the automatic
  // exposure's percentile, so each LED is exposed for its brightest pixel
  // (peaks at 50-80% of full scale keep the LED positions' noise low).
  bool highlight_target = false;
};

class DomeDemo {
 public:
  explicit DomeDemo(const DomeDemoOptions& options) : o_(options), rig_(load_rig(options.rig)) {
    if (o_.noise != "none" && o_.noise != "physical") fail("--noise: '{}' is not none or physical", o_.noise);
    if (o_.camera != "sim" && o_.camera != "dslr") fail("--camera: '{}' is not sim or dslr", o_.camera);
    if (dslr() && !(rig_.trigger.shutter_lag_us > 0 && rig_.trigger.arrival_timeout_us > 0)) {
      fail(
          "--camera dslr: rig '{}' ({}) describes no stills camera on its trigger (trigger.shutter_lag_us "
          "and "
          "trigger.arrival_timeout_us); use hw/rigs/sim-dome-dslr.yaml",
          rig_.name, o_.rig.string());
    }
    if (!(o_.dslr_drop_rate >= 0 && o_.dslr_drop_rate < 1))
      fail("--dslr-drop-rate must be in [0, 1), got {}", o_.dslr_drop_rate);
    register_file_cameras();
    if (o_.sphere_x_mm.size() < 2) fail("demo: the light calibration needs two sphere positions");
    sim::register_sim_camera();
  }

  nlohmann::json run() {
    const auto start = Clock::now();
    // No clamp at 1: values are normalised to the rig's nominal exposure, and
    // an LED exposed shorter than that legitimately reads above 1. The
    // settings are checked before any program starts.
    solve_ = o_.solve;
    solve_.no_clamp = true;
    solve_.resolve();
    // A demo starts afresh: what an earlier run wrote here goes (only what the demo writes).
    for (const char* written :
         {"scenes", "calibration", "capture", "result", "surface", "dome", "shots", "demo.json"})
      fs::remove_all(o_.out / written);
    fs::create_directories(o_.out);
    summary_ = {
        {"rig", o_.rig.string()}, {"scene", o_.scene}, {"method", o_.solve.method}, {"camera", o_.camera}};

    // 1. The chrome sphere at each position: the light calibration's input.
    std::vector<fs::path> chrome_stacks;
    for (std::size_t k = 0; k < o_.sphere_x_mm.size(); ++k) {
      const std::string name = fmt::format("chrome-{}", k + 1);
      const fs::path scene = o_.out / "scenes" / (name + ".yaml");
      fs::create_directories(scene.parent_path());
      std::ofstream(scene) << chrome_sphere_scene(o_.sphere_radius_mm, o_.sphere_x_mm[k],
                                                  rig_.object_position_mm.z());
      capture_stage({name, scene.string(), "", o_.out / "calibration" / name, true});
      chrome_stacks.push_back(o_.out / "calibration" / name);
    }

    // 2. Light directions and LED positions from the two sphere positions.
    const fs::path calibration_dir = o_.out / "calibration";
    calibrate(chrome_stacks, calibration_dir);

    // 3. The object, with the capture's exposure choice (automatic by default).
    const fs::path stack = o_.out / "capture";
    capture_stage({"object", o_.scene, o_.material, stack, false});
    write_ground_truth(stack);

    // 4. Normals with the calibrated near lights, 5. a surface, 6. the report.
    const fs::path result = o_.out / "result";
    solve(stack, calibration_dir / "calibration.json", result);
    const fs::path surface_dir = o_.out / "surface";
    integrate(result, surface_dir);
    report(result, stack, calibration_dir / "calibration.json", surface_dir);

    summary_["seconds"] = seconds_since(start);
    summary_["out"] = o_.out.string();
    std::ofstream(o_.out / "demo.json") << summary_.dump(2) << "\n";
    return summary_;
  }

 private:
  bool dslr() const { return o_.camera == "dslr"; }

  // The simulated DSLR's shutter speed for a stage: a DSLR is set by hand, so
  // the capture takes it as a fixed exposure, near what the sim: camera's
  // automatic exposure picks (the chrome's highlights at half scale, the
  // object's brightest pixels at 70 %). Standard speeds: 1/8 s and 1/125 s.
  double dslr_exposure_us(const Stage& stage) const {
    if (!stage.highlight_target && o_.capture.exposure_us) return *o_.capture.exposure_us;
    return stage.highlight_target ? 125'000 : 8'000;
  }

  void say(const std::string& text) const {
    if (o_.mode == OutputMode::kHuman) fmt::print("{}\n", text);
    logger("host")->debug("{}", text);
  }

  std::vector<std::string> camera_args(const Stage& stage) const {
    std::vector<std::string> args = {
        "--scene", stage.scene, "--noise", o_.noise, "--seed", std::to_string(o_.seed), "--lights", "near"};
    if (!stage.material.empty()) args.insert(args.end(), {"--material", stage.material});
    if (o_.width) args.insert(args.end(), {"--width", std::to_string(*o_.width)});
    if (o_.height) args.insert(args.end(), {"--height", std::to_string(*o_.height)});
    return args;
  }

  // Starts the two programs for this stage's scene (the operator places the
  // target), captures every LED into stage.stack and stops them again.
  void capture_stage(const Stage& stage) {
    const auto start = Clock::now();
    SimulatedDomeOptions dome_options;
    dome_options.rig = o_.rig;
    dome_options.log_dir = o_.out / "dome" / stage.name;
    dome_options.socket_dir = sockets_.path() / stage.name;
    dome_options.program_dir = o_.programs;
    dome_options.sim_args = camera_args(stage);
    dome_options.camera = !dslr();
    // The DSLR's RAW files are the capture's originals: kept beside the stacks.
    const fs::path shots = o_.out / "shots" / stage.name;
    if (dslr()) {
      fs::create_directories(shots);
      for (const std::string& arg :
           {std::string("--dslr"), shots.string(), std::string("--dslr-exposure-us"),
            fmt::format("{:.0f}", dslr_exposure_us(stage)), std::string("--dslr-drop-rate"),
            fmt::format("{}", o_.dslr_drop_rate), std::string("--dslr-seed"), std::to_string(o_.seed)})
        dome_options.sim_args.push_back(arg);
      // With the half-press wired, the camera fires only with it (as some do): the firmware must press it.
      if (const auto& focus = rig_.trigger.focus) {
        dome_options.sim_args.push_back("--dslr-focus-line");
        dome_options.sim_args.push_back(focus->line.by_name() ? focus->line.name : "FOCUS");
      }
      dome_options.sim_args.insert(dome_options.sim_args.end(), o_.dslr_args.begin(), o_.dslr_args.end());
    }
    SimulatedDome dome(dome_options);
    CaptureReport report;
    try {
      auto controller = connect_controller(dome.controller_uri());
      auto camera = camera::open_camera_uri(dslr() ? "folder:" + shots.string() : dome.camera_uri());
      CaptureOptions capture = o_.capture;
      capture.out = stage.stack;
      if (dslr()) {
        capture.exposure_us = dslr_exposure_us(stage);
      } else if (stage.highlight_target) {
        capture.exposure_us.reset();
        capture.auto_percentile = 1.0;
        capture.auto_target = 0.7;
      }
      capture.mode = o_.mode == OutputMode::kHuman ? OutputMode::kHuman : OutputMode::kQuiet;
      report = capture_stack(rig_, *controller, *camera, capture);
    } catch (const std::exception& e) {
      throw Error(fmt::format("demo: capturing {} failed: {}\n(logs of the dome's programs in {})",
                              stage.name, e.what(), dome_options.log_dir.string()));
    }
    const auto codes = dome.stop();
    if (codes.firmware != 0) {
      logger("host")->warn("lightstage-domed exited with {} (log: {})", codes.firmware,
                           (dome_options.log_dir / "domed-1.log").string());
    }
    summary_["captures"][stage.name] = report.to_json();
    summary_["captures"][stage.name]["stack"] = stage.stack.string();
    say(fmt::format(
        "captured {:<9} {} frames + {} darks through lightstage-domed and {} in {:.1f} s ({} retaken) "
        "-> {}",
        stage.name, report.frames, report.dark_frames,
        dslr() ? "the simulated DSLR's files" : "the sim camera", seconds_since(start), report.retakes,
        stage.stack.string()));
  }

  void calibrate(const std::vector<fs::path>& stacks, const fs::path& out) {
    calibration::LightCalibrationOptions options;
    options.inputs = stacks;
    options.rig = o_.rig;
    options.dome_radius_mm = 0;  // triangulate: no help from the nominal dome
    options.sphere_z_mm = {rig_.object_position_mm.z()};
    const auto run = calibration::calibrate_lights(options);
    for (const auto& problem : run.calibration.problems) logger("host")->warn("{}", problem);
    nlohmann::json written = calibration::write_calibration_outputs(out, run, stacks);
    // The demo knows the true LEDs: how well did the calibration find them?
    double direction_mean = 0, direction_max = 0, position_mean = 0, position_max = 0;
    std::size_t positions = 0, measured = 0;
    for (std::size_t i = 0; i < run.calibration.lights.size() && i < rig_.leds.size(); ++i) {
      const auto& light = run.calibration.lights[i];
      if (!light.measured) continue;
      ++measured;
      const double angle = angle_between_deg(light.direction, rig_.light_direction(rig_.leds[i]));
      direction_mean += angle;
      direction_max = std::max(direction_max, angle);
      if (light.position_mm) {
        const double error = (*light.position_mm - rig_.leds[i].position_mm).norm();
        position_mean += error;
        position_max = std::max(position_max, error);
        ++positions;
      }
    }
    if (measured > 0) direction_mean /= static_cast<double>(measured);
    if (positions > 0) position_mean /= static_cast<double>(positions);
    summary_["calibration"] = {{"folder", out.string()},
                               {"lights", run.calibration.lights.size()},
                               {"measured", measured},
                               {"direction_error_deg", {{"mean", direction_mean}, {"max", direction_max}}},
                               {"position_error_mm", {{"mean", position_mean}, {"max", position_max}}},
                               {"seconds", run.seconds}};
    say(fmt::format(
        "calibrated {} of {} lights from {} sphere positions in {:.1f} s: directions {:.3f} deg mean "
        "({:.3f} max), LED positions {:.2f} mm mean ({:.2f} max) against the simulator's -> {}",
        measured, run.calibration.lights.size(), stacks.size(), run.seconds, direction_mean, direction_max,
        position_mean, position_max, out.string()));
  }

  // The simulator knows the object exactly: its normals, depth and outline
  // beside the captured frames let solve and report measure the error.
  void write_ground_truth(const fs::path& stack) const {
    sim::SimulateOptions options;
    options.scene = o_.scene;
    options.material = o_.material;
    options.width = o_.width;
    options.height = o_.height;
    options.light_model = sim::LightModel::kNear;
    const sim::World world(rig_, options);
    const auto& truth = world.renderer().ground_truth();
    cv::Mat mask;
    cv::compare(world.renderer().mask(), 0, mask, cv::CMP_GT);
    io::write_png(stack / "mask.png", mask);
    io::write_normal_map(stack / "Normal_gt.png", truth.normals, mask);
    if (!truth.depth.empty()) io::write_pfm(stack / "depth_gt.pfm", truth.depth);
  }

  void solve(const fs::path& stack, const fs::path& calibration_file, const fs::path& result) {
    SolveCalibration calibration;
    calibration.file = calibration_file;
    const auto start = Clock::now();
    const SolveReport solved = solve_folder(stack, solve_, result, calibration);
    summary_["solve"] = {{"folder", result.string()}, {"seconds", seconds_since(start)}};
    if (solved.error) summary_["solve"]["error_vs_ground_truth"] = solved.error->to_json();
    say(fmt::format("solved with {} and the calibrated near lights in {:.1f} s -> {}", o_.solve.method,
                    seconds_since(start), result.string()));
    if (solved.error) say(solved.error->describe());
  }

  void integrate(const fs::path& result, const fs::path& out) {
    const io::SolveFolder solved = io::read_solve_folder(result);
    const surface::CameraModel camera = surface::CameraModel::orthographic(
        solved.normals.size(), rig_.camera.pixel_pitch_mm * static_cast<double>(rig_.camera.width) /
                                   static_cast<double>(solved.normals.cols));
    surface::IntegrationOptions integration;
    const surface::SurfaceResult surface =
        surface::integrate_normals(solved.normals, solved.solved, camera, integration);
    const cv::Mat albedo = solved.display_albedo();
    surface::SurfaceFiles files;
    files.ply = true;
    const nlohmann::json written =
        surface::write_surface_outputs(out, surface, camera, solved.normals, albedo, files, {});
    summary_["surface"] = {
        {"folder", out.string()}, {"pixels", surface.stats.pixels}, {"seconds", surface.stats.seconds}};
    say(fmt::format("integrated a surface over {} pixels in {:.1f} s -> {}", surface.stats.pixels,
                    surface.stats.seconds, out.string()));
  }

  void report(const fs::path& result, const fs::path& stack, const fs::path& calibration_file,
              const fs::path& surface_dir) {
    report::ReportOptions options;
    options.stack = stack;
    options.calibration = calibration_file;
    options.depth = surface_dir;
    const auto written = report::write_report(result, result / "report.html", options);
    summary_["report"] = written.file.string();
    say(fmt::format("report (open in a browser) -> {}", written.file.string()));
  }

  const DomeDemoOptions& o_;
  SolveSettings solve_;
  Rig rig_;
  SocketFolder sockets_;
  nlohmann::json summary_;
};

}  // namespace

std::string chrome_sphere_scene(double radius_mm, double x_mm, double z_mm) {
  // A chrome ball on a dark stand: the room is dim, so only the LED's reflection is bright.
  return fmt::format(
      "name: chrome-ball\nobject: {{type: sphere, radius_mm: {}, center_mm: [{}, 0, {}]}}\nmaterial: chrome\n"
      "environment_radiance: 0.05\n",
      radius_mm, x_mm, z_mm);
}

SolveSettings default_demo_solve() {
  SolveSettings settings;
  settings.shadow_threshold = 0.02;
  return settings;
}

nlohmann::json run_dome_demo(const DomeDemoOptions& options) { return DomeDemo(options).run(); }

}  // namespace lightstage::pipeline
