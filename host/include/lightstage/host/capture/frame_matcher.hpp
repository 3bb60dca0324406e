#pragma once
// Which camera frame belongs to which sequence step. The controller reports
// when it fired each trigger (its CLOCK_MONOTONIC); the camera stamps each
// frame (start of exposure or end of frame, on its own clock, converted to
// CLOCK_MONOTONIC before matching). A frame belongs to the step whose trigger
// it follows by no more than the camera's latency. A step without a frame was
// dropped (retake it); a frame without a step is a duplicate or stray (drop it).

#include "lightstage/common/camera.hpp"

#include <cstdint>
#include <optional>
#include <vector>

namespace lightstage {

struct StepTiming {
  std::int64_t trigger_ns = 0;  // controller clock (CLOCK_MONOTONIC)
  double exposure_us = 0;
};

struct FrameTiming {
  std::int64_t timestamp_ns = 0;  // already on CLOCK_MONOTONIC
  camera::TimestampPoint point = camera::TimestampPoint::kUnknown;
  std::uint64_t sequence = 0;
};

struct MatchOptions {
  // Trigger edge to start of exposure, at most (sensor and driver latency).
  std::int64_t max_start_latency_ns = 50'000'000;
  // End of exposure to the frame's end-of-frame stamp, at most (readout + transfer).
  std::int64_t max_readout_ns = 200'000'000;
};

struct FrameMatch {
  std::vector<std::optional<std::size_t>> frame_of_step;  // index into frames, per step
  std::vector<std::size_t> unmatched_frames;              // duplicates and strays
  std::size_t dropped() const;                            // steps without a frame
  // Gaps in the frames' sequence numbers (frames the device lost on the way).
  std::size_t sequence_gaps = 0;
};

FrameMatch match_frames(const std::vector<StepTiming>& steps, const std::vector<FrameTiming>& frames,
                        const MatchOptions& options = {});

}  // namespace lightstage
