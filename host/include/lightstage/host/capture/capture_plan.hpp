#pragma once
// What a capture takes, as plain data: the LEDs in stack order, each LED's
// exposure (with a bracket, its exposures too) as indices into one sorted list
// of exposures, and the exposures a dark is taken at. The functions here work
// out exposures from the rig, the camera's range and preview frames; none of
// them touches a device (capture_runner.hpp does).

#include "lightstage/common/camera.hpp"
#include "lightstage/common/rig.hpp"
#include "lightstage/host/capture/capture_options.hpp"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <vector>

namespace lightstage {

struct PlannedFrame {
  int led_id = -1;
  std::size_t exposure = 0;          // into CapturePlan::exposures_us: the LED's (HDR: its bracket's base)
  std::vector<std::size_t> bracket;  // HDR: into exposures_us, shortest first; empty without a bracket
};

struct CapturePlan {
  std::vector<PlannedFrame> frames;   // stack order
  std::vector<double> exposures_us;   // every exposure the plan names, ascending, each once
  std::vector<double> bracket_stops;  // empty = one exposure per LED
  int dark_frames = 0;                // averaged per taken exposure; 0 = no darks

  bool hdr() const { return !bracket_stops.empty(); }
  std::vector<int> led_ids() const;
  double exposure_us(std::size_t frame) const { return exposures_us.at(frames.at(frame).exposure); }
  // The exposures camera frames are taken at, ascending: each frame's own, or
  // with a bracket those of the brackets. A dark is taken at each.
  std::vector<std::size_t> taken_exposures() const;
  // Throws InputError naming the LED or exposure that does not fit (an index
  // out of range, an exposure not positive, a bracket missing or unsorted).
  void check() const;
};

// The LEDs to capture: `requested` in its order, or every LED of the rig in
// rig order. Throws for an id the rig does not have.
std::vector<int> plan_led_ids(const Rig& rig, const std::vector<int>& requested);

// The longest exposure an LED may be lit for (its on-time limit, open loop's
// margin included) and the camera allows.
double longest_exposure_us(const Led& led, const camera::ControlInfo& range, std::uint32_t settle_us);

// How long a step lights its LED after the settle time, open loop: the
// exposure with room for the camera's trigger latency.
std::uint32_t open_loop_on_us(double exposure_us);

// How long the controller lights a step's LED besides open_loop_on_us: the
// settle time (or the rig's half-press lead, when longer) and the camera's
// shutter lag (see the firmware's sequencer.hpp). What the `settle_us`
// parameters below take when they check on-time limits.
std::uint32_t lit_overhead_us(const TriggerLine& trigger, std::uint32_t settle_us);

// Closed loop: how long a step waits for the camera's strobe (its LED lit
// meanwhile): the exposure plus room for a late camera, but when an LED is lit
// (max_on_us > 0) no longer than its on-time limit leaves after `settle_us`.
std::uint32_t strobe_timeout_us(double exposure_us, double max_on_us, std::uint32_t settle_us);

// Every LED's on-time limit by id (0 = none known).
using OnTimeLimits = std::map<int, double>;

// Throws InputError naming the LED, exposure and limit when a planned shot
// (a frame's exposure or one of its bracket's) would light its LED for
// longer than its limit allows: checked before anything is taken, so the
// controller does not refuse a sequence half-way through a capture.
void check_on_time(const CapturePlan& plan, const OnTimeLimits& max_on_us, std::uint32_t settle_us);

// Takes one frame of each LED at one exposure, in the order given.
using PreviewFrames =
    std::function<std::vector<camera::Frame>(const std::vector<int>& led_ids, double exposure_us)>;

// Automatic exposure per LED from preview frames: the options' percentile of
// each preview is aimed at auto_target of full scale, in 1/6-stop steps from
// the start exposure (so LEDs share few exposures), within the camera's range
// and the LED's on-time limit. Clipped previews are taken again 3 stops
// shorter, up to 6 rounds; an LED still clipped gets the last preview's
// exposure (at least the camera's shortest).
std::map<int, double> auto_exposures(const Rig& rig, const std::vector<int>& led_ids,
                                     const camera::ControlInfo& range, const CaptureOptions& options,
                                     const PreviewFrames& preview);

// exposure_us · 2^stop for each stop, in whole microseconds within what the
// camera and the LED's on-time limit allow; shortest first, without repeats.
std::vector<double> bracket_exposures(const Led& led, double exposure_us, const std::vector<double>& stops,
                                      const camera::ControlInfo& range, std::uint32_t settle_us);

// The plan for `led_ids` from each LED's exposure and, when `stops` is not
// empty, its bracket (both by LED id; every planned LED must have them).
// Checked (CapturePlan::check) before it is returned.
CapturePlan make_plan(const std::vector<int>& led_ids, const std::map<int, double>& exposure_of,
                      const std::map<int, std::vector<double>>& bracket_of, const std::vector<double>& stops,
                      int dark_frames);

}  // namespace lightstage
