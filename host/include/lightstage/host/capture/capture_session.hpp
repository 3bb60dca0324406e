#pragma once
// A capture: the controller sequences the LEDs and triggers the camera; every
// frame is matched to its LED by trigger time, written as it lands (atomic
// file + rename, the stack index and manifest rewritten after each), so the
// folder is a loadable stack at every moment and an interrupted capture keeps
// every frame it took. `resume` picks up where the manifest says it stopped.
//
// Exposure: fixed, or automatic per LED from a preview pass (the brightest
// pixels aimed at a share of saturation). Dark frames per exposure are
// averaged, written, and named by each frame of that exposure (radiometry
// subtracts them pixel by pixel). With a bracket, every LED is taken at
// several exposures (one controller sequence per exposure) and the frames are
// merged into one float frame per LED (hdr_merge.hpp). Dropped frames are
// retaken; duplicates are dropped.
//
// This composes three parts: the plan (capture_plan.hpp: what to take), the
// runner (capture_runner.hpp: controller and camera through the plan) and the
// stack writer (stack_writer.hpp: the folder, incrementally, and resume).

#include "lightstage/common/camera.hpp"
#include "lightstage/common/rig.hpp"
#include "lightstage/host/capture/capture_options.hpp"
#include "lightstage/host/controller/controller_client.hpp"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <cstddef>
#include <string>
#include <vector>

namespace lightstage {

struct CaptureReport {
  std::size_t frames = 0;      // frames in the stack
  std::size_t taken_now = 0;   // frames taken by this run (less than `frames` when resumed)
  std::size_t retakes = 0;     // steps run again after a dropped frame
  std::size_t duplicates = 0;  // frames matched to no step
  std::size_t dark_frames = 0;
  std::size_t bracket_frames = 0;  // camera frames merged into this run's HDR frames
  double seconds = 0;              // wall time of the run
  double camera_wait_seconds = 0;  // time spent waiting for frames after the controller finished
  std::string message;
  nlohmann::json to_json() const;
};

// Throws InputError for bad options or a folder it must not touch, Error
// (saying the frames taken so far are kept, and to --resume) when the
// controller, the camera or the link fails.
CaptureReport capture_stack(const Rig& rig, ControllerClient& controller, camera::Camera& cam,
                            const CaptureOptions& options);

// One LED at each exposure in turn, frames as the camera gave them: the
// bracket for response calibration and linearity checks. Uses the options'
// loop, timing, gain and retakes; nothing is written.
std::vector<cv::Mat> capture_bracket(const Rig& rig, ControllerClient& controller, camera::Camera& cam,
                                     int led_id, const std::vector<double>& exposures_us,
                                     const CaptureOptions& options);

}  // namespace lightstage
