#include "lightstage/host/capture/capture_runner.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/host/capture/capture_plan.hpp"
#include "lightstage/host/capture/frame_matcher.hpp"
#include "lightstage/host/capture/shot_matcher.hpp"
#include "util/elapsed.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <mutex>
#include <set>
#include <thread>

namespace lightstage {
namespace {

using SteadyClock = std::chrono::steady_clock;

std::string led_name(int id) { return id < 0 ? std::string("dark") : fmt::format("LED {}", id); }

// What a shutter-speed dial shows: "1/125 s", "0.6 s", "2 s".
std::string shutter_speed_text(double exposure_us) {
  if (exposure_us < 1e6) return fmt::format("1/{:.0f} s", 1e6 / exposure_us);
  return fmt::format("{:g} s", exposure_us / 1e6);
}

}  // namespace

CaptureRunner::CaptureRunner(ControllerClient& controller, camera::Camera& cam, const CaptureOptions& options,
                             const TriggerLine& trigger)
    : controller_(controller), cam_(cam), options_(options), trigger_(trigger) {
  const bool strobe = controller_.info().capabilities().strobe_input();
  if (options_.loop == "closed" && !strobe) fail("--loop closed: the controller's rig has no strobe input");
  closed_loop_ = options_.loop == "closed" || (options_.loop == "auto" && strobe);
  hardware_ = std::ranges::count(cam_.trigger_modes(), camera::TriggerMode::kHardware) > 0;
}

void CaptureRunner::start() {
  camera::CameraConfig config = cam_.default_config();
  config.trigger = hardware_ ? camera::TriggerMode::kHardware : camera::TriggerMode::kSoftware;
  const camera::Validation v = cam_.validate(config);
  if (v.status == camera::ConfigStatus::kInvalid) {
    fail("{}: cannot configure for capture: {}", cam_.uri(), v.message());
  }
  cam_.configure(config);
  const camera::Controls now = cam_.set_controls({std::nullopt, options_.gain});
  gain_ = now.analogue_gain.value_or(1.0);
  cam_.start();
}

double CaptureRunner::max_on_us(int led_id) const {
  if (led_id < 0) return 0;
  for (const proto::Led& led : controller_.info().leds()) {
    if (static_cast<int>(led.id()) == led_id) return led.max_on_us();
  }
  return 0;
}

OnTimeLimits CaptureRunner::on_time_limits(const Rig& rig) const {
  OnTimeLimits limits;
  for (const Led& led : rig.leds) limits[led.id] = led.limits.max_on_us;
  for (const proto::Led& led : controller_.info().leds()) {
    // The controller enforces its own: the tighter one counts.
    const int id = static_cast<int>(led.id());
    if (led.max_on_us() > 0 && (!(limits[id] > 0) || led.max_on_us() < limits[id]))
      limits[id] = led.max_on_us();
  }
  return limits;
}

std::size_t CaptureRunner::steps_per_sequence() const {
  constexpr std::size_t kFramesPerSequence = 12;
  return std::clamp<std::size_t>(controller_.info().capabilities().max_sequence_steps(), 1,
                                 kFramesPerSequence);
}

void CaptureRunner::set_exposure(double exposure_us) {
  if (exposure_us == asked_exposure_us_) return;
  const camera::Controls now = cam_.set_controls({exposure_us, std::nullopt});
  asked_exposure_us_ = exposure_us;
  current_exposure_us_ = now.exposure_us.value_or(exposure_us);
  // Cameras that cannot say which frame a change reached (V4L2) need a few
  // frames to settle: take them dark and throw them away.
  const int latency = cam_.control_info().latency_frames;
  if (latency > 0 && hardware_) {
    try {
      run_batch_once(std::vector<Shot>(static_cast<std::size_t>(latency), Shot{-1, exposure_us}));
    } catch (const BatchAborted& aborted) {
      if (stop_asked()) throw CaptureStopped("the capture was stopped as asked");
      throw Error(aborted.what());  // its frames are thrown away: none belongs to the batch's shots
    }
  }
}

bool CaptureRunner::halt_asked() const { return options_.halt_requested && options_.halt_requested(); }

bool CaptureRunner::stop_asked() const {
  return halt_asked() || (!mid_group_ && options_.stop_requested && options_.stop_requested());
}

Batch CaptureRunner::run_batch(const std::vector<Shot>& shots) {
  if (shots.empty()) return {};
  if (stop_asked()) throw CaptureStopped("the capture was stopped as asked");
  set_exposure(shots.front().exposure_us);
  Batch batch = hardware_ ? run_batch_once(shots) : run_software_batch(shots);
  for (int attempt = 0; attempt < options_.max_retakes && batch.taken.size() < shots.size(); ++attempt) {
    if (halt_asked()) throw BatchAborted("the capture was halted (the dome darkened)", std::move(batch));
    std::vector<std::size_t> missing;
    for (std::size_t i = 0; i < shots.size(); ++i) {
      if (!batch.taken.count(i)) missing.push_back(i);
    }
    logger("capture")->warn("{} frame(s) dropped ({}...): retaking", missing.size(),
                            led_name(shots[missing[0]].led_id));
    std::vector<Shot> again;
    for (const std::size_t i : missing) again.push_back(shots[i]);
    Batch retake;
    try {
      retake = hardware_ ? run_batch_once(again) : run_software_batch(again);
    } catch (BatchAborted& aborted) {
      // What the first run and the aborted retake took, by shot of this batch.
      for (auto& [j, taken] : aborted.partial.taken) batch.taken[missing[j]] = std::move(taken);
      aborted.partial = std::move(batch);
      throw;
    }
    batch.retakes += again.size();
    batch.duplicates += retake.duplicates;
    batch.camera_wait_seconds += retake.camera_wait_seconds;
    for (auto& [j, taken] : retake.taken) batch.taken[missing[j]] = std::move(taken);
  }
  for (std::size_t i = 0; i < shots.size(); ++i) {
    if (!batch.taken.count(i)) {
      throw Error(fmt::format("{}: no frame for {} after {} retakes", cam_.uri(), led_name(shots[i].led_id),
                              options_.max_retakes));
    }
  }
  return batch;
}

// One controller sequence with the camera on hardware trigger, frames read on
// a thread of their own while the sequence runs, then matched by trigger time.
Batch CaptureRunner::run_batch_once(const std::vector<Shot>& shots) {
  // Lit for what the camera really exposes when it rounded up (a stills camera's nearest shutter speed).
  const double exposure_us = std::max(shots.front().exposure_us, current_exposure_us_);
  proto::Sequence sequence;
  sequence.set_id(next_sequence_id_++);
  for (std::size_t i = 0; i < shots.size(); ++i) {
    proto::Step* step = sequence.add_steps();
    if (shots[i].led_id >= 0) {
      auto* led = step->add_leds();
      led->set_led_id(static_cast<std::uint32_t>(shots[i].led_id));
      led->set_level(1.0f);
    }
    step->set_settle_us(options_.settle_us);
    step->set_trigger(true);
    // Open loop: lit a little longer than the exposure, for the camera's trigger latency.
    step->set_exposure_us(open_loop_on_us(exposure_us));
    step->set_wait_strobe(closed_loop_);
    // The controller counts the whole timeout against the LED's on-time limit.
    step->set_strobe_timeout_us(strobe_timeout_us(exposure_us, max_on_us(shots[i].led_id),
                                                  lit_overhead_us(trigger_, options_.settle_us)));
    step->set_gap_us(options_.gap_us);
    step->set_tag(static_cast<std::uint32_t>(i));
  }
  std::vector<camera::Frame> frames;
  std::mutex frames_mutex;
  std::atomic<bool> sequence_done{false};
  std::exception_ptr camera_error;
  // A stills camera's files may take up to the rig's arrival timeout after each exposure.
  const auto wait_limit = std::chrono::milliseconds(static_cast<std::int64_t>(
      1000 + 3 * exposure_us / 1000 + (trigger_.shutter_lag_us + trigger_.arrival_timeout_us) / 1000));
  std::thread reader([&] {
    // A camera may deliver well after the sequence (slow readout, a busy
    // link): while frames keep coming it is late, not dropping them, so the
    // wait counts from the later of the sequence's end and the last frame.
    SteadyClock::time_point quiet_since{};
    try {
      for (;;) {
        if (auto frame = cam_.wait_frame(std::chrono::milliseconds(20))) {
          const std::lock_guard lock(frames_mutex);
          frames.push_back(std::move(*frame));
          if (sequence_done) quiet_since = SteadyClock::now();
        }
        if (!sequence_done) continue;
        if (quiet_since == SteadyClock::time_point{}) quiet_since = SteadyClock::now();
        const std::lock_guard lock(frames_mutex);
        if (frames.size() >= shots.size() || SteadyClock::now() - quiet_since > wait_limit) return;
      }
    } catch (...) {
      camera_error = std::current_exception();
    }
  });
  SequenceRun run;
  try {
    // A halt that came after the check before this batch (or while it runs) ends it at its next step.
    bool aborted = false;
    run = controller_.run_sequence(sequence, [&](const proto::StepEvent&) {
      if (aborted || !halt_asked()) return;
      aborted = true;
      try {
        controller_.abort();
      } catch (const ControllerError&) {
        // It ended meanwhile.
      }
    });
  } catch (...) {
    sequence_done = true;
    reader.join();
    throw;
  }
  sequence_done = true;
  const SteadyClock::time_point controller_done = SteadyClock::now();
  reader.join();
  Batch batch;
  batch.camera_wait_seconds = seconds_since(controller_done);
  if (camera_error) std::rethrow_exception(camera_error);
  // Steps cut short by an abort are not exposed in full: their frames are not kept.
  std::erase_if(run.steps, [](const proto::StepEvent& e) { return e.outcome() != proto::OK; });
  std::vector<StepTiming> steps;
  for (const auto& e : run.steps) steps.push_back({e.trigger_ns(), exposure_us});
  const FrameMatch matched = match(steps, frames);
  batch.duplicates = matched.unmatched_frames.size();
  for (std::size_t k = 0; k < run.steps.size(); ++k) {
    if (!matched.frame_of_step[k]) continue;
    const std::size_t shot = run.steps[k].tag();
    check_stills_exposure(frames[*matched.frame_of_step[k]]);
    batch.taken[shot] = Taken{std::move(frames[*matched.frame_of_step[k]]), run.steps[k]};
  }
  if (!run.ok()) {
    throw BatchAborted(fmt::format("controller: sequence {} ended {} after {} of {} steps: {}", sequence.id(),
                                   proto::Outcome_Name(run.done.outcome()), run.steps.size(), shots.size(),
                                   run.done.detail()),
                       std::move(batch));
  }
  return batch;
}

// A stills camera is set by hand or to its nearest shutter speed: a shot far
// from what was asked is a camera set wrong, not a frame to keep.
void CaptureRunner::check_stills_exposure(const camera::Frame& frame) const {
  if (!frame.own_clock || !frame.controls_reported || !(frame.exposure_us > 0) || !(current_exposure_us_ > 0))
    return;
  constexpr double kSixthStop = 1.0 / 6;
  if (std::abs(std::log2(frame.exposure_us / current_exposure_us_)) <= kSixthStop) return;
  throw Error(fmt::format(
      "{}: {} was exposed {} but the capture asked {}: set the camera's shutter speed to {} (or capture with "
      "--exposure-us {:.0f})",
      cam_.uri(), frame.source_file, shutter_speed_text(frame.exposure_us),
      shutter_speed_text(current_exposure_us_), shutter_speed_text(current_exposure_us_), frame.exposure_us));
}

FrameMatch CaptureRunner::match(const std::vector<StepTiming>& steps,
                                const std::vector<camera::Frame>& frames) {
  if (std::ranges::any_of(frames, &camera::Frame::own_clock)) {
    if (!(trigger_.shutter_lag_us > 0)) {
      fail(
          "{}: a stills camera's files are matched to the LEDs by their time after each trigger, but the rig "
          "gives no trigger.shutter_lag_us (and trigger.arrival_timeout_us): set both (docs/rig-format.md)",
          cam_.uri());
    }
    std::vector<ShotTiming> shots;
    for (const auto& f : frames) shots.push_back({f.timestamp_ns, f.timestamp_resolution_ns, f.arrived_ns});
    const ShotMatch m =
        match_shots(steps, shots,
                    {std::llround(trigger_.shutter_lag_us * 1000),
                     std::llround(trigger_.arrival_timeout_us * 1000), camera_clock_offset_ns_});
    if (m.ambiguous) {
      logger("capture")->warn(
          "{}: {} files for {} steps and no way to tell which step lost its file: retaking them", cam_.uri(),
          frames.size(), steps.size());
    }
    if (m.clock_offset_ns) {
      // Over every file so far: the shutter lag's jitter averages out, a one-shot retake does not sway it.
      const auto files = static_cast<long double>(steps.size() - m.dropped());
      clock_offset_sum_ += static_cast<long double>(*m.clock_offset_ns) * files;
      clock_offset_files_ += files;
      camera_clock_offset_ns_ = std::llround(clock_offset_sum_ / clock_offset_files_);
    }
    return m;
  }
  std::vector<FrameTiming> timings;
  for (const auto& f : frames) {
    const std::int64_t t =
        f.clock == camera::ClockDomain::kUnknown
            ? f.timestamp_ns
            : camera::convert_timestamp_ns(f.timestamp_ns, f.clock, camera::ClockDomain::kMonotonic);
    timings.push_back({t, f.timestamp_point, f.sequence});
  }
  return match_frames(steps, timings);
}

// Cameras without a hardware trigger input: light the LED, trigger by software, wait.
Batch CaptureRunner::run_software_batch(const std::vector<Shot>& shots) {
  Batch batch;
  const auto timeout = std::chrono::milliseconds(static_cast<std::int64_t>(
      2000 + 3 * shots.front().exposure_us / 1000 + trigger_.arrival_timeout_us / 1000));
  for (std::size_t i = 0; i < shots.size(); ++i) {
    // One LED at a time, lit from here: a stop (the dome darkened) must not light the next.
    if (i > 0 && stop_asked()) throw BatchAborted("the capture was stopped as asked", std::move(batch));
    std::vector<std::pair<std::uint32_t, float>> leds;
    if (shots[i].led_id >= 0) leds.emplace_back(static_cast<std::uint32_t>(shots[i].led_id), 1.0f);
    controller_.set_leds(leds);
    const SteadyClock::time_point asked = SteadyClock::now();
    std::optional<camera::Frame> frame;
    try {
      cam_.trigger();
      frame = cam_.wait_frame(timeout);
    } catch (...) {
      // A camera error must not leave the LED lit until the watchdog notices.
      try {
        controller_.all_off();
      } catch (...) {
      }
      throw;
    }
    batch.camera_wait_seconds += seconds_since(asked);
    controller_.all_off();
    if (frame) batch.taken[i] = Taken{std::move(*frame), {}};
  }
  return batch;
}

Batch CaptureRunner::run_counted(const std::vector<Shot>& shots) {
  const auto count = [this](const Batch& batch) {
    stats_.retakes += batch.retakes;
    stats_.duplicates += batch.duplicates;
    stats_.camera_wait_seconds += batch.camera_wait_seconds;
  };
  try {
    Batch batch = run_batch(shots);
    count(batch);
    return batch;
  } catch (BatchAborted& aborted) {
    count(aborted.partial);
    throw;
  }
}

void CaptureRunner::take_frames(const CapturePlan& plan, const std::vector<bool>& done,
                                const FrameSink& on_frame) {
  const std::size_t max_steps = steps_per_sequence();
  const auto is_done = [&](std::size_t i) { return i < done.size() && done[i]; };
  if (!plan.hdr()) {
    for (std::size_t exposure = 0; exposure < plan.exposures_us.size(); ++exposure) {
      std::vector<Shot> shots;
      std::vector<std::size_t> frame_of;
      for (std::size_t i = 0; i < plan.frames.size(); ++i) {
        if (plan.frames[i].exposure == exposure && !is_done(i)) {
          shots.push_back({plan.frames[i].led_id, plan.exposures_us[exposure]});
          frame_of.push_back(i);
        }
      }
      for (std::size_t begin = 0; begin < shots.size(); begin += max_steps) {
        const std::size_t end = std::min(shots.size(), begin + max_steps);
        const std::vector<Shot> part(shots.begin() + static_cast<std::ptrdiff_t>(begin),
                                     shots.begin() + static_cast<std::ptrdiff_t>(end));
        const auto hand_on = [&](Batch& batch) {
          for (auto& [k, taken] : batch.taken) {
            std::vector<Take> takes{Take{exposure, std::move(taken)}};
            on_frame(frame_of[begin + k], takes);
          }
        };
        Batch batch;
        try {
          batch = run_counted(part);
        } catch (BatchAborted& aborted) {
          hand_on(aborted.partial);  // exposed before the abort: kept, not taken again
          if (stop_asked()) throw CaptureStopped("the capture was stopped as asked");
          throw;
        }
        hand_on(batch);
      }
    }
    return;
  }
  // An interruption loses at most one group's brackets; finished LEDs are kept.
  std::vector<std::vector<std::size_t>> by_exposure(plan.exposures_us.size());
  for (std::size_t i = 0; i < plan.frames.size(); ++i) {
    if (!is_done(i)) by_exposure[plan.frames[i].exposure].push_back(i);
  }
  for (const std::vector<std::size_t>& indices : by_exposure) {
    for (std::size_t begin = 0; begin < indices.size(); begin += max_steps) {
      const std::vector<std::size_t> group(
          indices.begin() + static_cast<std::ptrdiff_t>(begin),
          indices.begin() + static_cast<std::ptrdiff_t>(std::min(indices.size(), begin + max_steps)));
      std::set<std::size_t> exposures;
      for (const std::size_t i : group)
        exposures.insert(plan.frames[i].bracket.begin(), plan.frames[i].bracket.end());
      std::map<std::size_t, std::vector<Take>> takes_of;  // by frame index
      // A stop is honoured here, between groups: within one it waits for the group's last exposure.
      if (stop_asked()) throw CaptureStopped("the capture was stopped as asked");
      mid_group_ = true;
      struct GroupEnd {
        bool& mid_group;
        ~GroupEnd() { mid_group = false; }
      } group_end{mid_group_};
      for (const std::size_t exposure : exposures) {
        std::vector<Shot> shots;
        std::vector<std::size_t> owner;
        for (const std::size_t i : group) {
          if (std::ranges::count(plan.frames[i].bracket, exposure) == 0) continue;
          shots.push_back({plan.frames[i].led_id, plan.exposures_us[exposure]});
          owner.push_back(i);
        }
        const auto add = [&](Batch& batch) {
          for (auto& [k, taken] : batch.taken) takes_of[owner[k]].push_back(Take{exposure, std::move(taken)});
        };
        Batch batch;
        try {
          batch = run_counted(shots);
        } catch (BatchAborted& aborted) {
          // LEDs whose whole bracket is in by now are kept; the others are taken again on --resume.
          add(aborted.partial);
          for (const std::size_t i : group) {
            if (takes_of[i].size() == plan.frames[i].bracket.size()) on_frame(i, takes_of[i]);
          }
          mid_group_ = false;
          if (stop_asked()) throw CaptureStopped("the capture was stopped as asked");
          throw;
        }
        add(batch);
      }
      for (const std::size_t i : group) on_frame(i, takes_of.at(i));
    }
  }
}

}  // namespace lightstage
