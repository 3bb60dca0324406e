#include "lightstage/host/capture/frame_matcher.hpp"

#include <algorithm>
#include <limits>

namespace lightstage {

std::size_t FrameMatch::dropped() const {
  return static_cast<std::size_t>(std::count_if(frame_of_step.begin(), frame_of_step.end(),
                                                [](const auto& f) { return !f.has_value(); }));
}

FrameMatch match_frames(const std::vector<StepTiming>& steps, const std::vector<FrameTiming>& frames,
                        const MatchOptions& options) {
  FrameMatch match;
  match.frame_of_step.assign(steps.size(), std::nullopt);
  std::vector<bool> used(frames.size(), false);
  // Steps in trigger order take the earliest unused frame inside their window,
  // so a late frame of one step cannot steal the next step's.
  std::vector<std::size_t> order(steps.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return steps[a].trigger_ns < steps[b].trigger_ns; });
  for (std::size_t k = 0; k < order.size(); ++k) {
    const StepTiming& step = steps[order[k]];
    const std::int64_t next_trigger =
        k + 1 < order.size() ? steps[order[k + 1]].trigger_ns : std::numeric_limits<std::int64_t>::max();
    const auto exposure_ns = static_cast<std::int64_t>(step.exposure_us * 1000);
    std::optional<std::size_t> best;
    for (std::size_t f = 0; f < frames.size(); ++f) {
      if (used[f]) continue;
      const FrameTiming& frame = frames[f];
      std::int64_t lo = step.trigger_ns, hi = step.trigger_ns + options.max_start_latency_ns;
      if (frame.point == camera::TimestampPoint::kEndOfFrame) {
        lo = step.trigger_ns + exposure_ns;
        hi = lo + options.max_start_latency_ns + options.max_readout_ns;
      } else if (frame.point == camera::TimestampPoint::kUnknown) {
        hi = std::max(hi,
                      step.trigger_ns + exposure_ns + options.max_start_latency_ns + options.max_readout_ns);
      }
      // A start-of-exposure stamp after the next trigger belongs to that trigger.
      if (frame.point != camera::TimestampPoint::kEndOfFrame) hi = std::min(hi, next_trigger);
      if (frame.timestamp_ns < lo || frame.timestamp_ns > hi) continue;
      if (!best || frame.timestamp_ns < frames[*best].timestamp_ns) best = f;
    }
    if (best) {
      used[*best] = true;
      match.frame_of_step[order[k]] = best;
    }
  }
  for (std::size_t f = 0; f < frames.size(); ++f) {
    if (!used[f]) match.unmatched_frames.push_back(f);
  }
  std::vector<std::uint64_t> sequences;
  for (const auto& f : frames) sequences.push_back(f.sequence);
  std::sort(sequences.begin(), sequences.end());
  for (std::size_t i = 1; i < sequences.size(); ++i) {
    if (sequences[i] > sequences[i - 1] + 1) match.sequence_gaps += sequences[i] - sequences[i - 1] - 1;
  }
  return match;
}

}  // namespace lightstage
