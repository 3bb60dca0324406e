// `lightstage capture`: run the dome and the camera together and write a stack.
#include "commands.hpp"
#include "options.hpp"

#include "lightstage/host/capture/capture_session.hpp"
#include "lightstage/pipeline/dome_connection.hpp"

#include <fmt/format.h>

#include <memory>

namespace lightstage::cli {

void add_capture(CLI::App& app) {
  struct Args {
    std::string rig = default_rig_path().string();
    std::string controller;
    std::string camera;
    std::string exposure = "auto";
    std::vector<int> leds;
    OutputFlags output;
    CaptureOptions options;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand(
      "capture",
      "Capture a stack: the controller lights each LED in turn and triggers the camera.\n"
      "Frames are matched to LEDs by trigger time, dropped frames are retaken, and every frame is\n"
      "written as it lands: DIR is a loadable stack (DiLiGenT layout + manifest.json) at every\n"
      "moment, and --resume completes an interrupted capture. Exposure is fixed (--exposure-us N)\n"
      "or chosen per LED from a preview pass (auto); dark frames per exposure are subtracted pixel by "
      "pixel.\n"
      "--bracket takes every LED at several exposures and merges them into one HDR frame (float PFM).\n"
      "Every exposure is checked against its LED's on-time limit before anything is taken; a full disk\n"
      "stops the capture (ENOSPC) with the stack on disk whole, for --resume.\n"
      "Example: lightstage capture --controller unix:/run/lightstage/domed.sock --camera v4l2:/dev/video0 "
      "--out scans/coin");
  sub->add_option("--rig", args->rig, "rig description (YAML)")->capture_default_str();
  sub->add_option("--controller", args->controller, "controller URI: tcp:, unix:, serial:, usb:")->required();
  sub->add_option(
         "--camera", args->camera,
         "camera URI: v4l2:/dev/videoN, libcamera:ID, aravis:ID, gphoto2:[MODEL|PORT], folder:PATH (a "
         "tethering folder), sim:PATH")
      ->required();
  sub->add_option("--out", args->options.out, "stack folder to write")->required();
  sub->add_flag("--resume", args->options.resume,
                "complete the interrupted capture in --out (same LEDs, --bracket, --exposure-us and "
                "--dark-frames as planned)");
  sub->add_option("--exposure-us", args->exposure, "exposure in us, or auto (per LED, from a preview)")
      ->capture_default_str();
  sub->add_option("--auto-target", args->options.auto_target,
                  "auto: the brightest pixels' level as a share of full scale")
      ->capture_default_str();
  sub->add_option("--gain", args->options.gain, "analogue gain (default: the camera's)");
  sub->add_option("--dark-frames", args->options.dark_frames, "dark frames averaged per exposure (0 = none)")
      ->capture_default_str();
  sub->add_option("--max-retakes", args->options.max_retakes, "retakes of a dropped frame before giving up")
      ->capture_default_str();
  sub->add_option("--loop", args->options.loop, "open, closed (wait for the camera's strobe) or auto")
      ->capture_default_str();
  sub->add_option("--settle-us", args->options.settle_us, "LED on to trigger")->capture_default_str();
  sub->add_option("--gap-us", args->options.gap_us, "dark time between frames")->capture_default_str();
  sub->add_option("--leds", args->leds, "LED ids to capture, in order (default: all)")->delimiter(',');
  sub->add_option("--bracket", args->options.bracket_stops,
                  "HDR: stops relative to each LED's exposure, e.g. 0,-3,-6; the frames of each LED are "
                  "merged into one float PFM frame per exposure-second (docs/capture.md)")
      ->delimiter(',');
  sub->add_option(
      "--response", args->options.response,
      "the camera's inverse response (lightstage camera response): frames are linearised to float PFM");
  add_output_flags(*sub, args->output, "the capture report: frames, retakes, darks, timings, out");
  sub->callback([sub, args] {
    apply_output_flags(*sub, args->output);
    CaptureOptions options = args->options;
    options.exposure_us = parse_exposure_us(args->exposure);
    options.led_ids = args->leds;
    options.mode = args->output.mode();
    pipeline::DomeConnection dome = pipeline::connect_dome(args->rig, args->controller, args->camera);
    const CaptureReport report = capture_stack(dome.rig, *dome.controller, *dome.camera, options);
    if (args->output.json) {
      nlohmann::json j = report.to_json();
      j["out"] = options.out.string();
      fmt::print("{}\n", j.dump());
    } else if (args->output.human()) {
      fmt::print("{}: {}\n", options.out.string(), report.message);
    }
  });
}

}  // namespace lightstage::cli
