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

#include "lightstage/common/camera.hpp"
#include "lightstage/common/rig.hpp"
#include "lightstage/host/controller/controller_client.hpp"
#include "lightstage/host/progress.hpp"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace lightstage {

struct CaptureOptions {
  std::filesystem::path out;
  bool resume = false;
  std::optional<double> exposure_us;  // fixed exposure; unset = automatic per LED
  double auto_start_us = 0;           // automatic: the preview exposure; 0 = the rig camera's
  double auto_target = 0.7;           // automatic: where the brightest pixels should sit, share of full scale
  double auto_percentile = 0.999;     // automatic: which pixels count as "the brightest"
  std::optional<double> gain;         // unset = the camera's current gain
  int dark_frames = 4;                // per exposure; 0 = no darks (black level 0)
  int max_retakes = 3;                // per step, for dropped frames
  std::string loop = "auto";          // open | closed | auto (closed when the rig has a strobe)
  std::uint32_t settle_us = 500;
  std::uint32_t gap_us = 500;
  std::vector<int> led_ids;  // empty = every LED of the rig, in rig order
  // HDR: stops relative to each LED's exposure (fixed or automatic), e.g.
  // {0, -3, -6}; every LED is taken at each and the frames merged into one
  // PFM frame in full scale per exposure-second. Empty = one exposure per LED.
  std::vector<double> bracket_stops;
  // The camera's inverse response (response_curve.hpp) for cameras that are
  // not linear: frames and darks are linearised and written as float PFM.
  std::filesystem::path response;
  OutputMode mode = OutputMode::kHuman;

  void check() const;  // throws InputError naming the option
};

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

CaptureReport capture_stack(const Rig& rig, ControllerClient& controller, camera::Camera& cam,
                            const CaptureOptions& options);

// One LED at each exposure in turn, frames as the camera gave them: the
// bracket for response calibration and linearity checks. Uses the options'
// loop, timing, gain and retakes; nothing is written.
std::vector<cv::Mat> capture_bracket(const Rig& rig, ControllerClient& controller, camera::Camera& cam,
                                     int led_id, const std::vector<double>& exposures_us,
                                     const CaptureOptions& options);

}  // namespace lightstage
