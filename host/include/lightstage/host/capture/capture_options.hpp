#pragma once
// What `lightstage capture` is asked to do: shared by the planner, the runner
// and the stack writer of a capture (capture_session.hpp composes them).

#include "lightstage/common/error.hpp"
#include "lightstage/host/progress.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace lightstage {

// Where a capture is, after a frame was written.
struct CaptureProgress {
  std::size_t frames = 0;  // frames on disk (resumed ones included)
  std::size_t total = 0;   // frames planned
  int led_id = -1;         // the LED of the frame just written
  std::size_t taken_now = 0;
};

// The capture stopped because it was asked to, between two controller
// sequences (the dome dark): every frame taken is kept; resume completes it.
class CaptureStopped : public Error {
 public:
  using Error::Error;
};

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
  // For a program that follows the capture (the operator's station): told
  // after each frame is written, and asked before each controller sequence
  // (preview, darks, frames; an HDR bracket group is finished first) whether
  // to stop there (CaptureStopped). A halt (the dome darkened) stops at once:
  // the running sequence is aborted at its next step, no LED is lit again,
  // the frames exposed before are kept.
  std::function<void(const CaptureProgress&)> on_progress;
  std::function<bool()> stop_requested;
  std::function<bool()> halt_requested;

  void check() const;  // throws InputError naming the option
};

}  // namespace lightstage
