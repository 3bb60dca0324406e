#include "lightstage/host/capture/capture_plan.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/capture/hdr_merge.hpp"

#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <set>

namespace lightstage {
namespace {

// The index of `exposure_us` in the sorted, distinct `exposures_us` (it is there).
std::size_t index_of(const std::vector<double>& exposures_us, double exposure_us) {
  const auto it = std::lower_bound(exposures_us.begin(), exposures_us.end(), exposure_us);
  return static_cast<std::size_t>(it - exposures_us.begin());
}

}  // namespace

std::vector<int> CapturePlan::led_ids() const {
  std::vector<int> ids;
  for (const PlannedFrame& frame : frames) ids.push_back(frame.led_id);
  return ids;
}

std::vector<std::size_t> CapturePlan::taken_exposures() const {
  std::set<std::size_t> taken;
  for (const PlannedFrame& frame : frames) {
    if (hdr()) {
      taken.insert(frame.bracket.begin(), frame.bracket.end());
    } else {
      taken.insert(frame.exposure);
    }
  }
  return {taken.begin(), taken.end()};
}

void CapturePlan::check() const {
  for (std::size_t i = 0; i < exposures_us.size(); ++i) {
    if (!(exposures_us[i] > 0) || !std::isfinite(exposures_us[i]))
      fail("capture plan: exposure {} us is not a positive number", exposures_us[i]);
    if (i > 0 && !(exposures_us[i - 1] < exposures_us[i]))
      fail("capture plan: exposures must be ascending, {} us follows {} us", exposures_us[i],
           exposures_us[i - 1]);
  }
  if (dark_frames < 0) fail("capture plan: dark_frames must be >= 0, got {}", dark_frames);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const PlannedFrame& frame = frames[i];
    if (frame.exposure >= exposures_us.size())
      fail("capture plan: frame {} (LED {}) has no exposure", i + 1, frame.led_id);
    if (hdr() && frame.bracket.empty())
      fail("capture plan: frame {} (LED {}) has no bracket", i + 1, frame.led_id);
    if (!hdr() && !frame.bracket.empty())
      fail("capture plan: frame {} (LED {}) has a bracket, but no stops are planned", i + 1, frame.led_id);
    for (std::size_t k = 0; k < frame.bracket.size(); ++k) {
      if (frame.bracket[k] >= exposures_us.size() || (k > 0 && !(frame.bracket[k - 1] < frame.bracket[k]))) {
        fail(
            "capture plan: frame {} (LED {}): its bracket must be distinct planned exposures, shortest first",
            i + 1, frame.led_id);
      }
    }
  }
}

std::vector<int> plan_led_ids(const Rig& rig, const std::vector<int>& requested) {
  std::vector<int> ids;
  if (requested.empty()) {
    for (const Led& led : rig.leds) ids.push_back(led.id);
  } else {
    for (const int id : requested) ids.push_back(rig.led(id).id);  // throws for an unknown id
  }
  return ids;
}

std::uint32_t open_loop_on_us(double exposure_us) {
  // Less a rounding error's worth, so the longest exposure an LED allows fits its limit exactly.
  return static_cast<std::uint32_t>(std::ceil(exposure_us * 1.05 + 300 - 1e-6));
}

std::uint32_t lit_overhead_us(const TriggerLine& trigger, std::uint32_t settle_us) {
  return static_cast<std::uint32_t>(
      std::min(std::ceil(trigger.lead_us(settle_us) + trigger.shutter_lag_us), 4e9));
}

std::uint32_t strobe_timeout_us(double exposure_us, double max_on_us, std::uint32_t settle_us) {
  // A camera may start its exposure late (trigger latency, a busy link); the strobe says when it ends.
  constexpr double kLateCameraUs = 200'000;
  double timeout = std::max<double>(open_loop_on_us(exposure_us), exposure_us + kLateCameraUs);
  if (max_on_us > 0) timeout = std::min(timeout, std::floor(max_on_us - settle_us));
  return static_cast<std::uint32_t>(std::clamp(timeout, 1.0, 4e9));
}

void check_on_time(const CapturePlan& plan, const OnTimeLimits& max_on_us, std::uint32_t settle_us) {
  for (const PlannedFrame& frame : plan.frames) {
    const auto limit = max_on_us.find(frame.led_id);
    if (limit == max_on_us.end() || !(limit->second > 0)) continue;
    std::vector<std::size_t> exposures = frame.bracket;
    if (exposures.empty()) exposures.push_back(frame.exposure);
    for (const std::size_t e : exposures) {
      const double exposure_us = plan.exposures_us.at(e);
      const double on_us = settle_us + static_cast<double>(open_loop_on_us(exposure_us));
      if (on_us > limit->second) {
        fail(
            "capture: LED {} at {} us would be lit for {} us ({} us settle, half-press and shutter lag; "
            "exposure and trigger latency), over its max_on_us {} us; use a shorter --exposure-us (at "
            "most {:.0f} us) or --settle-us",
            frame.led_id, exposure_us, on_us, settle_us, limit->second,
            std::floor((limit->second - settle_us - 300) / 1.05));
      }
    }
  }
}

double longest_exposure_us(const Led& led, const camera::ControlInfo& range, std::uint32_t settle_us) {
  const double longest = std::min(range.exposure_max_us > 0 ? range.exposure_max_us : 1e12,
                                  (led.limits.max_on_us - settle_us - 300) / 1.05);
  return std::max(longest, 1.0);
}

std::map<int, double> auto_exposures(const Rig& rig, const std::vector<int>& led_ids,
                                     const camera::ControlInfo& range, const CaptureOptions& options,
                                     const PreviewFrames& preview_frames) {
  const double start = options.auto_start_us > 0 ? options.auto_start_us : rig.camera.exposure_us;
  std::map<int, double> exposure;
  std::vector<int> todo = led_ids;
  double preview = start;
  for (int round = 0; round < 6 && !todo.empty(); ++round) {
    const std::vector<camera::Frame> frames = preview_frames(todo, preview);
    std::vector<int> saturated;
    for (std::size_t i = 0; i < todo.size() && i < frames.size(); ++i) {
      const int id = todo[i];
      const camera::Frame& frame = frames[i];
      cv::Mat values;
      frame.image.reshape(1, 1).convertTo(values, CV_64F);
      cv::sort(values, values, cv::SORT_EVERY_ROW | cv::SORT_ASCENDING);
      const auto at = static_cast<int>(std::floor(options.auto_percentile * (values.cols - 1)));
      const double full = std::ldexp(1.0, frame.bit_depth) - 1;
      const double level = values.at<double>(0, at);
      if (level >= kClippedShare * full) {
        saturated.push_back(id);  // clipped: measure again shorter
        continue;
      }
      double e = preview * options.auto_target * full / std::max(level, 1.0);
      // Steps of 1/6 stop, so LEDs group into few exposures (one sequence each).
      e = start * std::exp2(std::round(6 * std::log2(e / start)) / 6);
      const double longest =
          longest_exposure_us(rig.led(id), range, lit_overhead_us(rig.trigger, options.settle_us));
      exposure[id] = std::clamp(e, std::max(range.exposure_min_us, 1.0), longest);
    }
    todo = saturated;
    preview /= 8;
  }
  for (const int id : todo) exposure[id] = std::max(range.exposure_min_us, preview);
  return exposure;
}

std::vector<double> bracket_exposures(const Led& led, double exposure_us, const std::vector<double>& stops,
                                      const camera::ControlInfo& range, std::uint32_t settle_us) {
  const double shortest = std::max(range.exposure_min_us, 1.0);
  const double longest = std::max(shortest, longest_exposure_us(led, range, settle_us));
  std::vector<double> exposures;
  for (const double stop : stops)
    exposures.push_back(std::clamp(std::round(exposure_us * std::exp2(stop)), shortest, longest));
  std::ranges::sort(exposures);
  exposures.erase(std::unique(exposures.begin(), exposures.end()), exposures.end());
  return exposures;
}

CapturePlan make_plan(const std::vector<int>& led_ids, const std::map<int, double>& exposure_of,
                      const std::map<int, std::vector<double>>& bracket_of, const std::vector<double>& stops,
                      int dark_frames) {
  CapturePlan plan;
  plan.bracket_stops = stops;
  plan.dark_frames = dark_frames;
  const bool hdr = !stops.empty();
  const auto exposure = [&](int id) {
    const auto it = exposure_of.find(id);
    if (it == exposure_of.end()) fail("capture plan: LED {} has no exposure", id);
    return it->second;
  };
  const auto bracket = [&](int id) -> const std::vector<double>& {
    const auto it = bracket_of.find(id);
    if (it == bracket_of.end()) fail("capture plan: LED {} has no bracket", id);
    return it->second;
  };
  for (const int id : led_ids) {
    plan.exposures_us.push_back(exposure(id));
    if (hdr) plan.exposures_us.insert(plan.exposures_us.end(), bracket(id).begin(), bracket(id).end());
  }
  std::ranges::sort(plan.exposures_us);
  plan.exposures_us.erase(std::unique(plan.exposures_us.begin(), plan.exposures_us.end()),
                          plan.exposures_us.end());
  for (const int id : led_ids) {
    PlannedFrame frame;
    frame.led_id = id;
    frame.exposure = index_of(plan.exposures_us, exposure(id));
    if (hdr) {
      for (const double e : bracket(id)) frame.bracket.push_back(index_of(plan.exposures_us, e));
    }
    plan.frames.push_back(std::move(frame));
  }
  plan.check();
  return plan;
}

}  // namespace lightstage
