#include "lightstage/host/capture/capture_session.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/host/capture/frame_matcher.hpp"
#include "lightstage/host/capture/hdr_merge.hpp"
#include "lightstage/host/capture/response_curve.hpp"
#include "lightstage/host/controller/sequences.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "util/atomic_file.hpp"
#include "util/utc_time.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <opencv2/core.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <thread>

namespace fs = std::filesystem;

namespace lightstage {
namespace {

using Clock = std::chrono::steady_clock;
constexpr int kCaptureFormatVersion = 1;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// One image the capture needs: an LED (or none, for a dark frame) at an exposure.
struct Shot {
  int led_id = -1;  // -1: dark
  double exposure_us = 0;
};

struct Taken {
  camera::Frame frame;
  proto::StepEvent step;
};

// Frames of one batch, keyed by the index of the shot in the batch.
struct Batch {
  std::map<std::size_t, Taken> taken;
  std::size_t duplicates = 0;
  std::size_t retakes = 0;
  double camera_wait_seconds = 0;
};

std::string led_name(int id) { return id < 0 ? std::string("dark") : fmt::format("LED {}", id); }

double full_scale(const camera::Frame& f) { return std::ldexp(1.0, f.bit_depth) - 1; }

// A raw value at or above this share of full scale counts as clipped.
constexpr double kClippedShare = 0.98;

// The longest exposure an LED may be lit for (its on-time limit, open loop's
// margin included) and the camera allows.
double longest_exposure_us(const Led& led, const camera::ControlInfo& range, std::uint32_t settle_us) {
  const double longest = std::min(range.exposure_max_us > 0 ? range.exposure_max_us : 1e12,
                                  (led.limits.max_on_us - settle_us - 300) / 1.05);
  return std::max(longest, 1.0);
}

class CaptureRun {
 public:
  CaptureRun(const Rig& rig, ControllerClient& controller, camera::Camera& cam, const CaptureOptions& options)
      : rig_(rig), controller_(controller), cam_(cam), options_(options) {
    const bool strobe = controller_.info().capabilities().strobe_input();
    if (options_.loop == "closed" && !strobe) fail("--loop closed: the controller's rig has no strobe input");
    closed_loop_ = options_.loop == "closed" || (options_.loop == "auto" && strobe);
    hardware_ = std::ranges::count(cam_.trigger_modes(), camera::TriggerMode::Hardware) > 0;
    if (!options_.response.empty()) response_ = InverseResponse::load(options_.response);
  }

  CaptureReport run();
  std::vector<cv::Mat> bracket(int led_id, const std::vector<double>& exposures_us);

 private:
  void configure_camera();
  void set_exposure(double exposure_us);
  Batch run_batch(const std::vector<Shot>& shots);
  Batch run_batch_once(const std::vector<Shot>& shots);
  Batch run_software_batch(const std::vector<Shot>& shots);
  std::map<double, double> take_darks(const std::set<double>& exposures);
  std::map<int, double> auto_exposures(const std::vector<int>& leds);
  std::vector<double> bracket_exposures(int led_id, double exposure_us);
  void take_single(Progress& progress, std::size_t max_steps, const std::set<double>& exposures);
  void take_brackets(Progress& progress, std::size_t max_steps);
  cv::Mat dark_image(double exposure_us);
  void load_previous();
  void add_frame(std::size_t plan_index, const Taken& taken);
  void add_hdr_frame(std::size_t plan_index, const std::vector<std::pair<double, Taken>>& bracket);
  void write_index(bool complete);

  const Rig& rig_;
  ControllerClient& controller_;
  camera::Camera& cam_;
  CaptureOptions options_;
  std::optional<InverseResponse> response_;
  bool closed_loop_ = false;
  bool hardware_ = false;
  double gain_ = 1;
  double current_exposure_us_ = 0;
  std::uint32_t next_sequence_id_ = 1;

  std::vector<int> plan_;                       // LED ids in stack order
  std::map<int, double> exposure_of_;           // per LED
  std::map<double, double> black_of_exposure_;  // dark-frame mean per exposure
  std::map<double, std::string> dark_file_of_exposure_;
  std::map<double, cv::Mat> dark_of_exposure_;     // as written: 16-bit DN, or linearised float
  std::map<int, std::vector<double>> bracket_of_;  // HDR: per LED, its exposures, shortest first
  std::map<std::size_t, Frame> frames_;            // by plan index: frames in the stack
  std::map<std::size_t, nlohmann::json> frame_extra_;
  CaptureReport report_;
};

void CaptureRun::configure_camera() {
  camera::CameraConfig config = cam_.default_config();
  config.trigger = hardware_ ? camera::TriggerMode::Hardware : camera::TriggerMode::Software;
  const camera::Validation v = cam_.validate(config);
  if (v.status == camera::ConfigStatus::Invalid) {
    fail("{}: cannot configure for capture: {}", cam_.uri(), v.message());
  }
  cam_.configure(config);
  const camera::Controls now = cam_.set_controls({std::nullopt, options_.gain});
  gain_ = now.analogue_gain.value_or(1.0);
  cam_.start();
}

void CaptureRun::set_exposure(double exposure_us) {
  if (exposure_us == current_exposure_us_) return;
  const camera::Controls now = cam_.set_controls({exposure_us, std::nullopt});
  current_exposure_us_ = now.exposure_us.value_or(exposure_us);
  // Cameras that cannot say which frame a change reached (V4L2) need a few
  // frames to settle: take them dark and throw them away.
  const int latency = cam_.control_info().latency_frames;
  if (latency > 0 && hardware_)
    run_batch_once(std::vector<Shot>(static_cast<std::size_t>(latency), Shot{-1, exposure_us}));
}

// Runs the shots (all at one exposure) and retakes dropped ones.
Batch CaptureRun::run_batch(const std::vector<Shot>& shots) {
  if (shots.empty()) return {};
  set_exposure(shots.front().exposure_us);
  Batch batch = hardware_ ? run_batch_once(shots) : run_software_batch(shots);
  for (int attempt = 0; attempt < options_.max_retakes && batch.taken.size() < shots.size(); ++attempt) {
    std::vector<std::size_t> missing;
    for (std::size_t i = 0; i < shots.size(); ++i) {
      if (!batch.taken.count(i)) missing.push_back(i);
    }
    logger("capture")->warn("{} frame(s) dropped ({}...): retaking", missing.size(),
                            led_name(shots[missing[0]].led_id));
    std::vector<Shot> again;
    for (const std::size_t i : missing) again.push_back(shots[i]);
    Batch retake = hardware_ ? run_batch_once(again) : run_software_batch(again);
    batch.retakes += again.size();
    batch.duplicates += retake.duplicates;
    batch.camera_wait_seconds += retake.camera_wait_seconds;
    for (auto& [j, taken] : retake.taken) batch.taken[missing[j]] = std::move(taken);
  }
  if (batch.taken.size() < shots.size()) {
    for (std::size_t i = 0; i < shots.size(); ++i) {
      if (!batch.taken.count(i)) {
        throw Error(fmt::format("{}: no frame for {} after {} retakes; the frames taken so far are kept",
                                cam_.uri(), led_name(shots[i].led_id), options_.max_retakes));
      }
    }
  }
  return batch;
}

// One controller sequence with the camera on hardware trigger, frames read on
// a thread of their own while the sequence runs, then matched by trigger time.
Batch CaptureRun::run_batch_once(const std::vector<Shot>& shots) {
  const double exposure_us = shots.front().exposure_us;
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
    step->set_exposure_us(static_cast<std::uint32_t>(std::ceil(exposure_us * 1.05 + 300)));
    step->set_wait_strobe(closed_loop_);
    step->set_strobe_timeout_us(static_cast<std::uint32_t>(std::min(4e9, 2 * exposure_us + 200'000)));
    step->set_gap_us(options_.gap_us);
    step->set_tag(static_cast<std::uint32_t>(i));
  }
  std::vector<camera::Frame> frames;
  std::mutex frames_mutex;
  std::atomic<bool> sequence_done{false};
  std::exception_ptr camera_error;
  const auto wait_limit = std::chrono::milliseconds(static_cast<int>(1000 + 3 * exposure_us / 1000));
  std::thread reader([&] {
    // A camera may deliver well after the sequence (slow readout, a busy
    // link): while frames keep coming it is late, not dropping them, so the
    // wait counts from the later of the sequence's end and the last frame.
    Clock::time_point quiet_since{};
    try {
      for (;;) {
        if (auto frame = cam_.wait_frame(std::chrono::milliseconds(20))) {
          const std::lock_guard lock(frames_mutex);
          frames.push_back(std::move(*frame));
          if (sequence_done) quiet_since = Clock::now();
        }
        if (!sequence_done) continue;
        if (quiet_since == Clock::time_point{}) quiet_since = Clock::now();
        const std::lock_guard lock(frames_mutex);
        if (frames.size() >= shots.size() || Clock::now() - quiet_since > wait_limit) return;
      }
    } catch (...) {
      camera_error = std::current_exception();
    }
  });
  SequenceRun run;
  const Clock::time_point started = Clock::now();
  try {
    run = controller_.run_sequence(sequence);
  } catch (...) {
    sequence_done = true;
    reader.join();
    throw;
  }
  sequence_done = true;
  const Clock::time_point controller_done = Clock::now();
  reader.join();
  Batch batch;
  batch.camera_wait_seconds = seconds_since(controller_done);
  (void)started;
  if (camera_error) std::rethrow_exception(camera_error);
  if (!run.ok()) {
    throw Error(fmt::format("controller: sequence {} ended {}: {}; the frames taken so far are kept",
                            sequence.id(), proto::Outcome_Name(run.done.outcome()), run.done.detail()));
  }
  std::vector<StepTiming> steps;
  for (const auto& e : run.steps) steps.push_back({e.trigger_ns(), exposure_us});
  std::vector<FrameTiming> timings;
  for (const auto& f : frames) {
    const std::int64_t t =
        f.clock == camera::ClockDomain::Unknown
            ? f.timestamp_ns
            : camera::convert_timestamp_ns(f.timestamp_ns, f.clock, camera::ClockDomain::Monotonic);
    timings.push_back({t, f.timestamp_point, f.sequence});
  }
  const FrameMatch match = match_frames(steps, timings);
  batch.duplicates = match.unmatched_frames.size();
  for (std::size_t k = 0; k < run.steps.size(); ++k) {
    if (!match.frame_of_step[k]) continue;
    const std::size_t shot = run.steps[k].tag();
    batch.taken[shot] = Taken{std::move(frames[*match.frame_of_step[k]]), run.steps[k]};
  }
  return batch;
}

// Cameras without a hardware trigger input: light the LED, trigger by software, wait.
Batch CaptureRun::run_software_batch(const std::vector<Shot>& shots) {
  Batch batch;
  const auto timeout =
      std::chrono::milliseconds(static_cast<int>(2000 + 3 * shots.front().exposure_us / 1000));
  for (std::size_t i = 0; i < shots.size(); ++i) {
    std::vector<std::pair<std::uint32_t, float>> leds;
    if (shots[i].led_id >= 0) leds.emplace_back(static_cast<std::uint32_t>(shots[i].led_id), 1.0f);
    controller_.set_leds(leds);
    const Clock::time_point asked = Clock::now();
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

std::map<double, double> CaptureRun::take_darks(const std::set<double>& exposures) {
  std::map<double, double> black;
  for (const double exposure : exposures) {
    if (options_.dark_frames == 0) {
      black[exposure] = 0;
      continue;
    }
    if (dark_file_of_exposure_.count(exposure)) continue;  // resumed: already taken
    const Batch batch =
        run_batch(std::vector<Shot>(static_cast<std::size_t>(options_.dark_frames), Shot{-1, exposure}));
    cv::Mat sum;
    for (const auto& [i, taken] : batch.taken) {
      cv::Mat f;
      (response_ ? response_->linearise(taken.frame.image) : taken.frame.image).convertTo(f, CV_64F);
      sum = sum.empty() ? f : sum + f;
    }
    cv::Mat dark;
    sum.convertTo(dark, response_ ? CV_32F : CV_16U, 1.0 / static_cast<double>(batch.taken.size()));
    const std::string name = fmt::format("dark_{:.0f}us.{}", exposure, response_ ? "pfm" : "png");
    if (response_) {
      io::write_pfm(options_.out / name, dark);
    } else {
      io::write_png(options_.out / name, dark);
    }
    dark_file_of_exposure_[exposure] = name;
    black_of_exposure_[exposure] = cv::mean(dark)[0];
    dark_of_exposure_[exposure] = dark;
    report_.dark_frames += batch.taken.size();
  }
  return black;
}

std::map<int, double> CaptureRun::auto_exposures(const std::vector<int>& leds) {
  const camera::ControlInfo range = cam_.control_info();
  const double start = options_.auto_start_us > 0 ? options_.auto_start_us : rig_.camera.exposure_us;
  std::map<int, double> exposure;
  std::vector<int> todo = leds;
  double preview = start;
  for (int round = 0; round < 6 && !todo.empty(); ++round) {
    std::vector<Shot> shots;
    for (const int id : todo) shots.push_back({id, preview});
    const Batch batch = run_batch(shots);
    std::vector<int> saturated;
    for (const auto& [i, taken] : batch.taken) {
      const int id = shots[i].led_id;
      cv::Mat values;
      taken.frame.image.reshape(1, 1).convertTo(values, CV_64F);
      cv::sort(values, values, cv::SORT_EVERY_ROW | cv::SORT_ASCENDING);
      const auto at = static_cast<int>(std::floor(options_.auto_percentile * (values.cols - 1)));
      const double full = full_scale(taken.frame);
      const double level = values.at<double>(0, at);
      if (level >= kClippedShare * full) {
        saturated.push_back(id);  // clipped: measure again shorter
        continue;
      }
      double e = preview * options_.auto_target * full / std::max(level, 1.0);
      // Steps of 1/6 stop, so LEDs group into few exposures (one sequence each).
      e = start * std::exp2(std::round(6 * std::log2(e / start)) / 6);
      const double longest = longest_exposure_us(rig_.led(id), range, options_.settle_us);
      exposure[id] = std::clamp(e, std::max(range.exposure_min_us, 1.0), longest);
    }
    todo = saturated;
    preview /= 8;
  }
  for (const int id : todo) exposure[id] = std::max(range.exposure_min_us, preview);
  return exposure;
}

void CaptureRun::add_frame(std::size_t plan_index, const Taken& taken) {
  const int id = plan_[plan_index];
  const Led& led = rig_.led(id);
  const double exposure = taken.frame.exposure_us > 0 ? taken.frame.exposure_us : exposure_of_[id];
  Frame frame;
  frame.filename = fmt::format("{:03}.{}", plan_index + 1, response_ ? "pfm" : "png");
  frame.image = response_ ? response_->linearise(taken.frame.image) : taken.frame.image;
  frame.led_id = id;
  frame.led_position_mm = led.position_mm;
  frame.light_direction = rig_.light_direction(led);
  // Radiometry divides by this: values become radiance per the rig's reference exposure and gain.
  const double scale = (exposure / rig_.camera.exposure_us) * (taken.frame.analogue_gain / rig_.camera.gain);
  frame.light_intensity = Vec3::Constant(led.relative_intensity * scale);
  frame.exposure_us = exposure;
  frame.gain = taken.frame.analogue_gain;
  frame.black_level = black_of_exposure_.count(exposure_of_[id]) ? black_of_exposure_[exposure_of_[id]] : 0;
  if (dark_file_of_exposure_.count(exposure_of_[id])) {
    frame.dark_file = dark_file_of_exposure_[exposure_of_[id]];
    frame.dark = dark_image(exposure_of_[id]);
  }
  if (response_) {
    io::write_pfm(options_.out / frame.filename, frame.image);
  } else {
    io::write_png(options_.out / frame.filename, frame.image);
  }
  nlohmann::json extra = {{"frame_sequence", taken.frame.sequence},
                          {"frame_timestamp_ns", taken.frame.timestamp_ns},
                          {"frame_clock", std::string(camera::to_string(taken.frame.clock))},
                          {"trigger_ns", taken.step.trigger_ns()},
                          {"leds_on_ns", taken.step.leds_on_ns()},
                          {"leds_off_ns", taken.step.leds_off_ns()}};
  frames_[plan_index] = std::move(frame);
  frame_extra_[plan_index] = std::move(extra);
  ++report_.taken_now;
}

cv::Mat CaptureRun::dark_image(double exposure_us) {
  if (const auto it = dark_of_exposure_.find(exposure_us); it != dark_of_exposure_.end()) return it->second;
  const auto file = dark_file_of_exposure_.find(exposure_us);
  if (file == dark_file_of_exposure_.end()) return {};         // no darks: black level 0
  cv::Mat dark = io::read_image(options_.out / file->second);  // taken before an interruption
  dark_of_exposure_[exposure_us] = dark;
  return dark;
}

// base · 2^stop for each stop, in whole microseconds within what the camera
// and the LED's on-time limit allow; shortest first, without repeats.
std::vector<double> CaptureRun::bracket_exposures(int led_id, double exposure_us) {
  const camera::ControlInfo range = cam_.control_info();
  const double shortest = std::max(range.exposure_min_us, 1.0);
  const double longest = std::max(shortest, longest_exposure_us(rig_.led(led_id), range, options_.settle_us));
  std::set<double> exposures;
  for (const double stop : options_.bracket_stops)
    exposures.insert(std::clamp(std::round(exposure_us * std::exp2(stop)), shortest, longest));
  return {exposures.begin(), exposures.end()};
}

// One LED's bracket, merged into one float frame per exposure-second.
void CaptureRun::add_hdr_frame(std::size_t plan_index, const std::vector<std::pair<double, Taken>>& bracket) {
  const int id = plan_[plan_index];
  const Led& led = rig_.led(id);
  std::vector<HdrSample> samples;
  nlohmann::json exposures = nlohmann::json::array(), details = nlohmann::json::array();
  for (const auto& [planned, taken] : bracket) {
    const double exposure = taken.frame.exposure_us > 0 ? taken.frame.exposure_us : planned;
    samples.push_back({taken.frame.image, dark_image(planned), exposure});
    exposures.push_back(exposure);
    nlohmann::json detail = {{"exposure_us", exposure},
                             {"frame_sequence", taken.frame.sequence},
                             {"frame_timestamp_ns", taken.frame.timestamp_ns},
                             {"frame_clock", std::string(camera::to_string(taken.frame.clock))},
                             {"trigger_ns", taken.step.trigger_ns()},
                             {"leds_on_ns", taken.step.leds_on_ns()},
                             {"leds_off_ns", taken.step.leds_off_ns()}};
    if (dark_file_of_exposure_.count(planned)) detail["dark"] = dark_file_of_exposure_[planned];
    details.push_back(std::move(detail));
  }
  HdrMergeOptions merge_options;
  merge_options.sensor_full_scale = full_scale(bracket.front().second.frame);
  merge_options.saturation_dn = kClippedShare * merge_options.sensor_full_scale;
  merge_options.response = response_ ? &*response_ : nullptr;
  const HdrMerge merged = merge_hdr(samples, merge_options);
  for (std::size_t i = 0; i < details.size(); ++i) details[i]["clipped_values"] = merged.clipped[i];

  const double gain = bracket.front().second.frame.analogue_gain;
  Frame frame;
  frame.filename = fmt::format("{:03}.pfm", plan_index + 1);
  frame.image = merged.image;
  frame.led_id = id;
  frame.led_position_mm = led.position_mm;
  frame.light_direction = rig_.light_direction(led);
  // Values are per exposure-second: as if exposed for 1 s, dark already subtracted.
  constexpr double kSecondUs = 1e6;
  const double scale = (kSecondUs / rig_.camera.exposure_us) * (gain / rig_.camera.gain);
  frame.light_intensity = Vec3::Constant(led.relative_intensity * scale);
  frame.exposure_us = kSecondUs;
  frame.gain = gain;
  frame.black_level = 0;
  frame.saturation_level = merged.saturation_level;
  io::write_pfm(options_.out / frame.filename, frame.image);
  frames_[plan_index] = std::move(frame);
  frame_extra_[plan_index] = {{"bracket_exposures_us", exposures},
                              {"bracket", details},
                              {"hdr_saturated_values", merged.saturated_values}};
  ++report_.taken_now;
  report_.bracket_frames += bracket.size();
}

// One batch per exposure, LEDs in plan order within it.
void CaptureRun::take_single(Progress& progress, std::size_t max_steps, const std::set<double>& exposures) {
  for (const double exposure : exposures) {
    std::vector<Shot> shots;
    std::vector<std::size_t> plan_index;
    for (std::size_t i = 0; i < plan_.size(); ++i) {
      if (exposure_of_[plan_[i]] == exposure && !frames_.count(i)) {
        shots.push_back({plan_[i], exposure});
        plan_index.push_back(i);
      }
    }
    for (std::size_t begin = 0; begin < shots.size(); begin += max_steps) {
      const std::size_t end = std::min(shots.size(), begin + max_steps);
      const std::vector<Shot> part(shots.begin() + static_cast<std::ptrdiff_t>(begin),
                                   shots.begin() + static_cast<std::ptrdiff_t>(end));
      Batch batch = run_batch(part);
      report_.retakes += batch.retakes;
      report_.duplicates += batch.duplicates;
      report_.camera_wait_seconds += batch.camera_wait_seconds;
      for (auto& [k, taken] : batch.taken) {
        add_frame(plan_index[begin + k], taken);
        write_index(false);  // the folder stays a loadable stack of every frame on disk
        progress.advance();
      }
    }
  }
}

// LEDs grouped by their exposure and cut into groups of one sequence's
// length; each group is taken at each of its bracket exposures (one sequence
// per exposure, shortest first), then merged and written LED by LED. An
// interruption loses at most one group's brackets; finished LEDs are kept.
void CaptureRun::take_brackets(Progress& progress, std::size_t max_steps) {
  std::map<double, std::vector<std::size_t>> by_exposure;
  for (std::size_t i = 0; i < plan_.size(); ++i) {
    if (!frames_.count(i)) by_exposure[exposure_of_[plan_[i]]].push_back(i);
  }
  for (const auto& [base, indices] : by_exposure) {
    for (std::size_t begin = 0; begin < indices.size(); begin += max_steps) {
      const std::vector<std::size_t> group(
          indices.begin() + static_cast<std::ptrdiff_t>(begin),
          indices.begin() + static_cast<std::ptrdiff_t>(std::min(indices.size(), begin + max_steps)));
      std::set<double> exposures;
      for (const std::size_t i : group) {
        for (const double e : bracket_of_.at(plan_[i])) exposures.insert(e);
      }
      std::map<std::size_t, std::vector<std::pair<double, Taken>>> brackets;
      for (const double exposure : exposures) {
        std::vector<Shot> shots;
        std::vector<std::size_t> owner;
        for (const std::size_t i : group) {
          if (std::ranges::count(bracket_of_.at(plan_[i]), exposure) == 0) continue;
          shots.push_back({plan_[i], exposure});
          owner.push_back(i);
        }
        Batch batch = run_batch(shots);
        report_.retakes += batch.retakes;
        report_.duplicates += batch.duplicates;
        report_.camera_wait_seconds += batch.camera_wait_seconds;
        for (auto& [k, taken] : batch.taken) brackets[owner[k]].emplace_back(exposure, std::move(taken));
      }
      for (const std::size_t i : group) {
        add_hdr_frame(i, brackets.at(i));
        write_index(false);
        progress.advance();
      }
    }
  }
}

void CaptureRun::write_index(bool complete) {
  ImageStack stack;
  nlohmann::json extra_frames = nlohmann::json::array();
  std::vector<int> done;
  for (const auto& [i, frame] : frames_) {
    stack.frames.push_back(frame);
    extra_frames.push_back(frame_extra_[i]);
    done.push_back(static_cast<int>(i));
  }
  nlohmann::json exposures = nlohmann::json::object();
  for (const auto& [id, e] : exposure_of_) exposures[std::to_string(id)] = e;
  nlohmann::json darks = nlohmann::json::object();
  for (const auto& [e, file] : dark_file_of_exposure_)
    darks[fmt::format("{:.0f}", e)] = {{"file", file}, {"mean", black_of_exposure_[e]}, {"exposure_us", e}};
  nlohmann::json brackets = nlohmann::json::object();
  for (const auto& [id, list] : bracket_of_) brackets[std::to_string(id)] = list;
  const camera::CameraInfo cam = cam_.info();
  nlohmann::json extra = {
      {"capture",
       {{"version", kCaptureFormatVersion},
        {"complete", complete},
        {"plan_led_ids", plan_},
        {"done", done},
        {"exposure_us", exposures},
        {"gain", gain_},
        {"loop", closed_loop_ ? "closed" : "open"},
        {"trigger", hardware_ ? "hardware" : "software"},
        {"darks", darks},
        {"bracket_stops", options_.bracket_stops},
        {"bracket_exposure_us", brackets},
        {"camera", {{"uri", cam.uri}, {"model", cam.model}, {"driver", cam.driver}}},
        {"controller",
         {{"firmware", controller_.info().firmware_version()}, {"rig", controller_.info().rig_name()}}},
        {"updated", util::utc_timestamp()}}},
      {"rig", {{"name", rig_.name}, {"file", rig_.source.string()}}},
      {"frames", extra_frames}};
  if (stack.frames.empty()) {
    // Nothing to index yet: keep the plan where resume can find it.
    util::write_text_atomic(
        options_.out / "manifest.json",
        nlohmann::json{{"format", "lightstage-stack"}, {"version", 1}, {"capture", extra["capture"]}}.dump(
            2));
    return;
  }
  io::write_stack(options_.out, stack, extra, /*write_images=*/false);
}

void CaptureRun::load_previous() {
  const fs::path manifest_path = options_.out / "manifest.json";
  if (!fs::exists(manifest_path)) return;
  nlohmann::json manifest;
  try {
    std::ifstream in(manifest_path);
    manifest = nlohmann::json::parse(in);
  } catch (const std::exception& e) {
    fail("{}: cannot resume: {}", manifest_path.string(), e.what());
  }
  if (!manifest.contains("capture"))
    fail("{}: cannot resume: not a capture (no 'capture' key)", manifest_path.string());
  const auto& c = manifest["capture"];
  if (c.value("version", 0) != kCaptureFormatVersion) {
    fail("{}: capture.version {} is not {}", manifest_path.string(), c.value("version", 0),
         kCaptureFormatVersion);
  }
  const auto planned = c.at("plan_led_ids").get<std::vector<int>>();
  if (planned != plan_) {
    fail("{}: cannot resume: it was planned for other LEDs ({} of them) than this run ({})",
         manifest_path.string(), planned.size(), plan_.size());
  }
  const auto stops = c.value("bracket_stops", std::vector<double>{});
  if (stops != options_.bracket_stops) {
    fail("{}: cannot resume: it was planned with bracket stops [{}], this run asks for [{}]",
         manifest_path.string(), fmt::join(stops, ","), fmt::join(options_.bracket_stops, ","));
  }
  for (const auto& [id, e] : c.at("exposure_us").items()) exposure_of_[std::stoi(id)] = e.get<double>();
  if (c.contains("bracket_exposure_us")) {
    for (const auto& [id, list] : c.at("bracket_exposure_us").items())
      bracket_of_[std::stoi(id)] = list.get<std::vector<double>>();
  }
  for (const auto& [key, d] : c.at("darks").items()) {
    // The exact exposure (the key is rounded to whole microseconds).
    const double e = d.value("exposure_us", std::stod(key));
    dark_file_of_exposure_[e] = d.at("file").get<std::string>();
    black_of_exposure_[e] = d.at("mean").get<double>();
  }
  // The frames the manifest lists (written after each frame's image, so every
  // frame it names is complete on disk; a frame in flight when the capture
  // stopped is simply taken again).
  const auto done = c.at("done").get<std::vector<std::size_t>>();
  const auto& listed = manifest.contains("frames") ? manifest.at("frames") : nlohmann::json::array();
  for (std::size_t k = 0; k < done.size() && k < listed.size(); ++k) {
    const auto& entry = listed[k];
    if (done[k] >= plan_.size())
      fail("{}: capture.done[{}] = {} is past the plan", manifest_path.string(), k, done[k]);
    Frame frame;
    frame.filename = entry.at("file").get<std::string>();
    frame.image = io::read_image(options_.out / frame.filename);
    frame.led_id = entry.at("led_id").get<int>();
    if (frame.led_id != plan_[done[k]]) {
      fail("{}: frames[{}] is LED {}, but the plan has LED {} there", manifest_path.string(), k, frame.led_id,
           plan_[done[k]]);
    }
    const auto vec = [&](const char* key) {
      const auto v = entry.at(key).get<std::vector<double>>();
      if (v.size() != 3) fail("{}: frames[{}].{} must have 3 numbers", manifest_path.string(), k, key);
      return Vec3(v[0], v[1], v[2]);
    };
    frame.light_direction = vec("light_direction");
    frame.light_intensity = vec("light_intensity");
    if (entry.contains("led_position_mm")) frame.led_position_mm = vec("led_position_mm");
    frame.exposure_us = entry.value("exposure_us", 0.0);
    frame.gain = entry.value("gain", 1.0);
    frame.black_level = entry.value("black_level", 0.0);
    frame.saturation_level = entry.value("saturation_level", 0.0);
    frame.dark_file = entry.value("dark", std::string());
    nlohmann::json extra = entry;
    for (const char* key :
         {"index", "file", "led_id", "light_direction", "light_intensity", "led_position_mm", "exposure_us",
          "gain", "black_level", "saturation_level", "dark"}) {
      extra.erase(key);
    }
    frames_[done[k]] = std::move(frame);
    frame_extra_[done[k]] = std::move(extra);
  }
  logger("capture")->info("resuming {}: {} of {} frames already taken", options_.out.string(), frames_.size(),
                          plan_.size());
}

CaptureReport CaptureRun::run() {
  const Clock::time_point started = Clock::now();
  if (options_.led_ids.empty()) {
    for (const Led& led : rig_.leds) plan_.push_back(led.id);
  } else {
    for (const int id : options_.led_ids) plan_.push_back(rig_.led(id).id);  // throws for an unknown id
  }
  const bool exists = fs::exists(options_.out) && !fs::is_empty(options_.out);
  if (exists && !options_.resume) {
    fail(
        "{}: the folder exists and is not empty (use --resume to complete an interrupted capture, or another "
        "--out)",
        options_.out.string());
  }
  fs::create_directories(options_.out);
  if (options_.resume) {
    try {
      load_previous();
    } catch (const nlohmann::json::exception& e) {
      fail("{}: cannot resume: {}", (options_.out / "manifest.json").string(), e.what());
    }
  }

  configure_camera();
  struct StopCamera {
    camera::Camera& cam;
    ~StopCamera() {
      try {
        cam.stop();
      } catch (const std::exception&) {
      }
    }
  } stop_camera{cam_};

  // Exposures: fixed, automatic, or as planned before an interruption.
  std::vector<int> unplanned;
  for (const int id : plan_) {
    if (!exposure_of_.count(id)) unplanned.push_back(id);
  }
  if (!unplanned.empty()) {
    if (options_.exposure_us) {
      for (const int id : unplanned) exposure_of_[id] = *options_.exposure_us;
    } else {
      for (const auto& [id, e] : auto_exposures(unplanned)) exposure_of_[id] = e;
    }
  }
  const bool hdr = !options_.bracket_stops.empty();
  if (hdr) {
    for (const int id : plan_) {
      if (!bracket_of_.count(id)) bracket_of_[id] = bracket_exposures(id, exposure_of_.at(id));
    }
  }
  write_index(false);
  std::set<double> exposures;  // every exposure a frame is taken at: one dark each
  for (const auto& [id, e] : exposure_of_) exposures.insert(e);
  if (hdr) {
    exposures.clear();
    for (const int id : plan_) exposures.insert(bracket_of_[id].begin(), bracket_of_[id].end());
  }
  take_darks(exposures);
  write_index(false);

  Progress progress("capture", plan_.size(), "frames", options_.mode);
  progress.advance(frames_.size());
  // Short sequences: frames are matched and written after each, so an
  // interruption loses at most one sequence's worth of frames.
  constexpr std::size_t kFramesPerSequence = 12;
  const std::size_t max_steps =
      std::clamp<std::size_t>(controller_.info().capabilities().max_sequence_steps(), 1, kFramesPerSequence);
  if (hdr) {
    take_brackets(progress, max_steps);
  } else {
    take_single(progress, max_steps, exposures);
  }
  progress.finish();
  write_index(true);
  report_.frames = frames_.size();
  report_.seconds = seconds_since(started);
  report_.message = fmt::format(
      "{} frames in {:.1f} s ({} taken now, {} retaken, {} duplicates dropped, {} dark{})", report_.frames,
      report_.seconds, report_.taken_now, report_.retakes, report_.duplicates, report_.dark_frames,
      hdr ? fmt::format(", HDR from {} bracket frames", report_.bracket_frames) : std::string());
  return report_;
}

std::vector<cv::Mat> CaptureRun::bracket(int led_id, const std::vector<double>& exposures_us) {
  rig_.led(led_id);  // throws for an unknown id
  configure_camera();
  std::vector<cv::Mat> images;
  for (const double e : exposures_us) {
    Batch batch = run_batch({Shot{led_id, e}});
    images.push_back(batch.taken.at(0).frame.image);
  }
  cam_.stop();
  return images;
}

}  // namespace

void CaptureOptions::check() const {
  if (out.empty()) fail("capture: --out is required");
  if (exposure_us && !(*exposure_us > 0))
    fail("capture: --exposure-us must be positive, got {}", *exposure_us);
  if (!(auto_target > 0 && auto_target < 1))
    fail("capture: --auto-target must be in (0, 1), got {}", auto_target);
  if (!(auto_percentile > 0 && auto_percentile <= 1)) {
    fail("capture: --auto-percentile must be in (0, 1], got {}", auto_percentile);
  }
  if (gain && !(*gain > 0)) fail("capture: --gain must be positive, got {}", *gain);
  if (dark_frames < 0) fail("capture: --dark-frames must be >= 0, got {}", dark_frames);
  if (max_retakes < 0) fail("capture: --max-retakes must be >= 0, got {}", max_retakes);
  if (loop != "open" && loop != "closed" && loop != "auto") {
    fail("capture: --loop must be open, closed or auto, got '{}'", loop);
  }
  if (!bracket_stops.empty()) {
    if (bracket_stops.size() < 2)
      fail("capture: --bracket needs at least 2 stops, got {}", bracket_stops.size());
    std::set<double> seen;
    for (const double stop : bracket_stops) {
      if (!(std::abs(stop) <= 16)) fail("capture: --bracket stop {} is not within [-16, 16]", stop);
      if (!seen.insert(stop).second) fail("capture: --bracket stop {} is given twice", stop);
    }
  }
}

nlohmann::json CaptureReport::to_json() const {
  return {{"frames", frames},           {"taken_now", taken_now},
          {"retakes", retakes},         {"duplicates", duplicates},
          {"dark_frames", dark_frames}, {"bracket_frames", bracket_frames},
          {"seconds", seconds},         {"camera_wait_seconds", camera_wait_seconds},
          {"message", message}};
}

CaptureReport capture_stack(const Rig& rig, ControllerClient& controller, camera::Camera& cam,
                            const CaptureOptions& options) {
  options.check();
  CaptureRun run(rig, controller, cam, options);
  try {
    return run.run();
  } catch (const InputError&) {
    throw;
  } catch (const Error& e) {
    // The controller, the camera or the link failed: say what is kept and how to go on.
    std::string message = e.what();
    if (message.find("the frames taken so far are kept") == std::string::npos) {
      message += "; the frames taken so far are kept";
    }
    throw Error(fmt::format("{} in {} (complete it with --resume)", message, options.out.string()));
  }
}

std::vector<cv::Mat> capture_bracket(const Rig& rig, ControllerClient& controller, camera::Camera& cam,
                                     int led_id, const std::vector<double>& exposures_us,
                                     const CaptureOptions& options) {
  if (exposures_us.empty()) fail("bracket: no exposures given");
  for (const double e : exposures_us) {
    if (!(e > 0)) fail("bracket: exposure {} us is not positive", e);
  }
  CaptureRun run(rig, controller, cam, options);
  return run.bracket(led_id, exposures_us);
}

}  // namespace lightstage
