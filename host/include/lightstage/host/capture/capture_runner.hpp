#pragma once
// Drives the controller and the camera through a capture plan. A batch is a
// list of shots at one exposure: with a hardware trigger one controller
// sequence, the frames read while it runs and matched to its steps by trigger
// time (frame_matcher.hpp); without, LED by LED with a software trigger.
// Dropped frames are retaken, frames matched to no step dropped as duplicates.

#include "lightstage/common/camera.hpp"
#include "lightstage/common/rig.hpp"
#include "lightstage/host/capture/capture_options.hpp"
#include "lightstage/host/capture/capture_plan.hpp"
#include "lightstage/host/capture/frame_matcher.hpp"
#include "lightstage/host/controller/controller_client.hpp"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace lightstage {

// One image the capture needs: an LED (or none, for a dark frame) at an exposure.
struct Shot {
  int led_id = -1;  // -1: dark
  double exposure_us = 0;
};

struct Taken {
  camera::Frame frame;
  proto::StepEvent step;  // the controller's record of the step; empty with a software trigger
};

// Frames of one batch, keyed by the index of the shot in the batch.
struct Batch {
  std::map<std::size_t, Taken> taken;
  std::size_t duplicates = 0;
  std::size_t retakes = 0;
  double camera_wait_seconds = 0;
};

// The controller ended a batch's sequence early (its watchdog, a safety limit,
// a shutdown): the message says how; `partial` holds the shots exposed in full
// before it, with their frames, so they are kept rather than taken again.
class BatchAborted : public Error {
 public:
  BatchAborted(const std::string& message, Batch taken_so_far)
      : Error(message), partial(std::move(taken_so_far)) {}
  Batch partial;
};

// One camera frame of a planned frame: at the plan's exposure `exposure` (an index into exposures_us).
struct Take {
  std::size_t exposure = 0;
  Taken taken;
};

// Batches of the plan's frames (take_frames), added up.
struct RunStats {
  std::size_t retakes = 0;     // shots run again after a dropped frame
  std::size_t duplicates = 0;  // frames matched to no step
  double camera_wait_seconds = 0;
};

class CaptureRunner {
 public:
  // Closed loop with --loop closed, or auto and a strobe input on the rig;
  // throws InputError for closed without one. Hardware trigger when the camera
  // has one. `trigger` is the rig's: a stills camera's shutter lag and its
  // files' arrival timeout (how frames are matched and waited for).
  CaptureRunner(ControllerClient& controller, camera::Camera& cam, const CaptureOptions& options,
                const TriggerLine& trigger = {});

  // Configures the camera for the trigger, sets the options' gain and starts streaming.
  void start();
  void stop() { cam_.stop(); }

  bool closed_loop() const { return closed_loop_; }
  bool hardware_trigger() const { return hardware_; }
  double gain() const { return gain_; }  // in force after start()
  // Shots per controller sequence: short, so an interruption loses little.
  std::size_t steps_per_sequence() const;
  // Each LED's on-time limit: the rig's, or the controller's where it is tighter.
  OnTimeLimits on_time_limits(const Rig& rig) const;

  // The shots (all at one exposure) with dropped ones retaken up to
  // max_retakes times; throws Error naming the camera and LED when a shot
  // still has no frame, BatchAborted when the controller ends a sequence early.
  Batch run_batch(const std::vector<Shot>& shots);

  // Called with a planned frame's takes once all are in (shortest exposure first).
  using FrameSink = std::function<void(std::size_t frame, std::vector<Take>& takes)>;
  // Takes every frame of `plan` not `done` (by frame index). Without a
  // bracket: one batch per exposure (ascending), LEDs in plan order, cut into
  // sequences; each frame is handed on as its batch ends. With a bracket:
  // LEDs grouped by base exposure and cut into sequences; each group is taken
  // at each of its bracket exposures (one batch each, shortest first), then
  // handed on frame by frame. Adds to stats(). When the controller aborts a
  // batch, the frames complete by then are handed on before BatchAborted is
  // rethrown.
  void take_frames(const CapturePlan& plan, const std::vector<bool>& done, const FrameSink& on_frame);
  const RunStats& stats() const { return stats_; }

 private:
  void set_exposure(double exposure_us);
  double max_on_us(int led_id) const;  // as the controller reports it; 0 = unknown
  Batch run_batch_once(const std::vector<Shot>& shots);
  Batch run_software_batch(const std::vector<Shot>& shots);
  Batch run_counted(const std::vector<Shot>& shots);
  // Which frame goes with which step (frame_matcher.hpp, or shot_matcher.hpp for a stills camera's files).
  FrameMatch match(const std::vector<StepTiming>& steps, const std::vector<camera::Frame>& frames);
  void check_stills_exposure(const camera::Frame& frame) const;

  ControllerClient& controller_;
  camera::Camera& cam_;
  CaptureOptions options_;
  TriggerLine trigger_;
  // A stills camera's clock offset (shot_matcher.hpp), averaged over every file matched so far.
  std::optional<std::int64_t> camera_clock_offset_ns_;
  long double clock_offset_sum_ = 0, clock_offset_files_ = 0;
  bool closed_loop_ = false;
  bool hardware_ = false;
  // Within an HDR group: a stop waits for the group's last exposure, so its brackets are not lost.
  bool mid_group_ = false;
  bool stop_asked() const;  // CaptureOptions::stop_requested outside an HDR group, or a halt
  bool halt_asked() const;  // CaptureOptions::halt_requested
  double gain_ = 1;
  double asked_exposure_us_ = 0;
  double current_exposure_us_ = 0;  // what the camera said it applied
  std::uint32_t next_sequence_id_ = 1;
  RunStats stats_;
};

}  // namespace lightstage
