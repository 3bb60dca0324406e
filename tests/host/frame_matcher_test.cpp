#include "lightstage/host/capture/frame_matcher.hpp"

#include <gtest/gtest.h>

namespace lightstage {
namespace {

using camera::TimestampPoint;

std::vector<StepTiming> steps_every(std::int64_t period_ns, int n, double exposure_us) {
  std::vector<StepTiming> steps;
  for (int i = 0; i < n; ++i) steps.push_back({1'000'000'000 + i * period_ns, exposure_us});
  return steps;
}

TEST(FrameMatcher, StartOfExposureStampsFollowTheirTrigger) {
  const auto steps = steps_every(20'000'000, 5, 10'000);
  std::vector<FrameTiming> frames;
  for (int i = 0; i < 5; ++i) {
    frames.push_back({steps[static_cast<std::size_t>(i)].trigger_ns + 100'000,
                      TimestampPoint::kStartOfExposure, static_cast<std::uint64_t>(i)});
  }
  std::swap(frames[1], frames[3]);  // arrival order does not matter
  const FrameMatch m = match_frames(steps, frames);
  EXPECT_EQ(m.dropped(), 0u);
  EXPECT_TRUE(m.unmatched_frames.empty());
  EXPECT_EQ(*m.frame_of_step[1], 3u);
  EXPECT_EQ(*m.frame_of_step[3], 1u);
  EXPECT_EQ(m.sequence_gaps, 0u);
}

TEST(FrameMatcher, ADroppedFrameLeavesItsStepEmptyAndShowsAsASequenceGap) {
  const auto steps = steps_every(20'000'000, 4, 10'000);
  std::vector<FrameTiming> frames;
  for (int i : {0, 1, 3}) {
    frames.push_back({steps[static_cast<std::size_t>(i)].trigger_ns + 50'000,
                      TimestampPoint::kStartOfExposure, static_cast<std::uint64_t>(i)});
  }
  const FrameMatch m = match_frames(steps, frames);
  EXPECT_EQ(m.dropped(), 1u);
  EXPECT_FALSE(m.frame_of_step[2]);
  EXPECT_EQ(*m.frame_of_step[3], 2u) << "the next step's frame is not shifted onto the dropped one";
  EXPECT_EQ(m.sequence_gaps, 1u);
}

TEST(FrameMatcher, DuplicatesAndStraysAreLeftOver) {
  const auto steps = steps_every(20'000'000, 2, 10'000);
  const std::vector<FrameTiming> frames = {
      {steps[0].trigger_ns + 10'000, TimestampPoint::kStartOfExposure, 0},
      {steps[0].trigger_ns + 20'000, TimestampPoint::kStartOfExposure, 1},  // a second frame for one trigger
      {steps[1].trigger_ns + 10'000, TimestampPoint::kStartOfExposure, 2},
      {steps[0].trigger_ns - 5'000'000, TimestampPoint::kStartOfExposure, 3},  // before any trigger
  };
  const FrameMatch m = match_frames(steps, frames);
  EXPECT_EQ(m.dropped(), 0u);
  EXPECT_EQ(*m.frame_of_step[0], 0u);
  EXPECT_EQ(*m.frame_of_step[1], 2u);
  EXPECT_EQ(m.unmatched_frames, (std::vector<std::size_t>{1, 3}));
}

TEST(FrameMatcher, EndOfFrameStampsComeAfterTheExposure) {
  // V4L2-style stamps: after the exposure and readout, which may pass the next trigger.
  const auto steps = steps_every(12'000'000, 3, 10'000);
  std::vector<FrameTiming> frames;
  for (int i = 0; i < 3; ++i) {
    frames.push_back({steps[static_cast<std::size_t>(i)].trigger_ns + 10'000'000 + 15'000'000,
                      TimestampPoint::kEndOfFrame, static_cast<std::uint64_t>(i)});
  }
  const FrameMatch m = match_frames(steps, frames);
  EXPECT_EQ(m.dropped(), 0u);
  for (std::size_t i = 0; i < 3; ++i) EXPECT_EQ(*m.frame_of_step[i], i);
  // A start-of-exposure stamp that late would belong to the next trigger instead.
  frames[0].point = TimestampPoint::kStartOfExposure;
  frames[0].timestamp_ns = steps[1].trigger_ns + 1000;
  const FrameMatch late = match_frames(steps, {frames[0]});
  EXPECT_FALSE(late.frame_of_step[0]);
  EXPECT_EQ(*late.frame_of_step[1], 0u);
}

}  // namespace
}  // namespace lightstage
