// Files of a stills camera matched to the controller's steps: stamps on the
// camera's own clock (an unknown offset), a random shutter lag, files late.
#include "lightstage/host/capture/shot_matcher.hpp"

#include <gtest/gtest.h>

#include <random>

namespace lightstage {
namespace {

constexpr std::int64_t kMs = 1'000'000;
constexpr std::int64_t kPeriod = 200 * kMs;  // lag 120 ms + exposure 10 ms + settle and gap
constexpr std::int64_t kLag = 120 * kMs;

std::vector<StepTiming> steps_of(int n, std::int64_t period = kPeriod) {
  std::vector<StepTiming> steps;
  for (int i = 0; i < n; ++i) steps.push_back({5'000 * kMs + i * period, 10'000});
  return steps;
}

// The file of each step in `taken`: stamp = trigger + offset + lag (ms
// resolution), arriving 300..900 ms after its exposure, in order.
std::vector<ShotTiming> files_of(const std::vector<StepTiming>& steps, const std::vector<int>& taken,
                                 std::int64_t offset, std::uint32_t seed = 1) {
  std::mt19937 random(seed);
  std::uniform_int_distribution<std::int64_t> lag(40 * kMs, kLag), delay(300 * kMs, 900 * kMs);
  std::vector<ShotTiming> files;
  std::int64_t last_arrival = 0;
  for (const int s : taken) {
    const StepTiming& step = steps[static_cast<std::size_t>(s)];
    const std::int64_t start = step.trigger_ns + lag(random);
    last_arrival = std::max(last_arrival, start + 10 * kMs + delay(random));
    files.push_back({(start + offset) / kMs * kMs, kMs, last_arrival});
  }
  return files;
}

const ShotMatchOptions kOptions{kLag, 2'000 * kMs, std::nullopt};

TEST(ShotMatcher, EveryFileFindsItsStepWhateverTheCameraClockSays) {
  const auto steps = steps_of(12);
  std::vector<int> all(12);
  for (int i = 0; i < 12; ++i) all[static_cast<std::size_t>(i)] = i;
  for (const std::int64_t offset : {std::int64_t{0}, 3'600'000 * kMs + 17 * kMs, -42'123 * kMs}) {
    auto files = files_of(steps, all, offset);
    std::swap(files[2], files[7]);  // the order handed in does not matter: stamps say it
    const ShotMatch m = match_shots(steps, files, kOptions);
    EXPECT_FALSE(m.ambiguous);
    EXPECT_EQ(m.dropped(), 0u);
    EXPECT_TRUE(m.unmatched_frames.empty());
    EXPECT_EQ(*m.frame_of_step[2], 7u);
    EXPECT_EQ(*m.frame_of_step[7], 2u);
    EXPECT_EQ(*m.frame_of_step[11], 11u);
    ASSERT_TRUE(m.clock_offset_ns);
    // The offset plus the mean lag drawn (40..120 ms).
    EXPECT_GE(*m.clock_offset_ns, offset + 40 * kMs);
    EXPECT_LE(*m.clock_offset_ns, offset + kLag);
  }
}

TEST(ShotMatcher, AMissingFileIsFoundOnceTheClockOffsetIsKnown) {
  // Steps as close as the controller allows: the lag, the exposure and 10 ms.
  const auto steps = steps_of(12, kLag + 20 * kMs);
  std::vector<int> taken;
  for (int i = 0; i < 12; ++i) {
    if (i != 0) taken.push_back(i);  // the first file never came
  }
  const std::int64_t offset = 7'000 * kMs;
  // Evenly spaced steps and no offset known: files 1..11 fit steps 0..10 as well as 1..11.
  const ShotMatch blind = match_shots(steps, files_of(steps, taken, offset), kOptions);
  EXPECT_TRUE(blind.ambiguous);
  EXPECT_EQ(blind.dropped(), 12u);  // all taken again rather than one LED's file filed under another
  EXPECT_EQ(blind.unmatched_frames.size(), 11u);
  // An earlier batch gave the offset (with its own lags): the right matching is the nearest one,
  // even with steps only a little further apart than the lag.
  const ShotMatch earlier =
      match_shots(steps, files_of(steps, {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}, offset, 7), kOptions);
  ASSERT_TRUE(earlier.clock_offset_ns);
  ShotMatchOptions known = kOptions;
  known.clock_offset_ns = earlier.clock_offset_ns;
  const ShotMatch m = match_shots(steps, files_of(steps, taken, offset), known);
  EXPECT_FALSE(m.ambiguous);
  EXPECT_EQ(m.dropped(), 1u);
  EXPECT_FALSE(m.frame_of_step[0]);
  for (std::size_t s = 1; s < 12; ++s) EXPECT_EQ(*m.frame_of_step[s], s - 1);
}

TEST(ShotMatcher, AMissingFileInTheMiddleIsFoundWithoutAnyOffset) {
  // The gap in the stamps shows where the file is missing.
  const auto steps = steps_of(10);
  const std::vector<int> taken = {0, 1, 2, 3, 5, 6, 7, 8, 9};
  const ShotMatch m = match_shots(steps, files_of(steps, taken, -5 * kMs), kOptions);
  EXPECT_FALSE(m.ambiguous);
  EXPECT_EQ(m.dropped(), 1u);
  EXPECT_FALSE(m.frame_of_step[4]);
  EXPECT_EQ(*m.frame_of_step[5], 4u);
}

// Every step got its file, one file (`left_over`) matched none, and step `step` took file `file`.
void expect_one_left_over(const ShotMatch& m, std::size_t left_over, std::size_t step, std::size_t file) {
  EXPECT_FALSE(m.ambiguous);
  EXPECT_EQ(m.dropped(), 0u);
  ASSERT_EQ(m.unmatched_frames.size(), 1u);
  EXPECT_EQ(m.unmatched_frames[0], left_over);
  ASSERT_TRUE(m.frame_of_step[step]);
  EXPECT_EQ(*m.frame_of_step[step], file);
}

TEST(ShotMatcher, AStrayFileFromAnEarlierBatchIsLeftOver) {
  const auto steps = steps_of(6);
  auto files = files_of(steps, {0, 1, 2, 3, 4, 5}, 0);
  // A retaken step's first file, late: stamped long before this batch.
  files.insert(files.begin(),
               ShotTiming{steps[0].trigger_ns - 3'000 * kMs, kMs, steps[0].trigger_ns + 50 * kMs});
  ShotMatchOptions options = kOptions;
  options.clock_offset_ns = 50 * kMs;
  expect_one_left_over(match_shots(steps, files, options), /*left_over=*/0, /*step=*/0, /*file=*/1);
}

TEST(ShotMatcher, AFileWithoutAStampAmongStampedOnesIsLeftOver) {
  const auto steps = steps_of(6);
  auto files = files_of(steps, {0, 1, 2, 3, 4, 5}, 900 * kMs);
  files.insert(files.begin() + 3, ShotTiming{0, 0, files[2].arrived_ns + 1});  // a foreign file, no EXIF time
  expect_one_left_over(match_shots(steps, files, kOptions), /*left_over=*/3, /*step=*/3, /*file=*/4);
}

TEST(ShotMatcher, AFileCannotBelongToAStepWhoseExposureEndedAfterItArrived) {
  // Without stamps only order and arrival count: the first file arrived
  // before step 1's exposure ended, so it is step 0's, and step 1 lost its file.
  const auto steps = steps_of(3);
  std::vector<ShotTiming> files = {{0, 0, steps[0].trigger_ns + 150 * kMs},
                                   {0, 0, steps[2].trigger_ns + 300 * kMs}};
  ShotMatchOptions options = kOptions;
  options.arrival_timeout_ns = 250 * kMs;  // nor the second file step 1's: it came too late for it
  const ShotMatch m = match_shots(steps, files, options);
  EXPECT_FALSE(m.ambiguous);
  EXPECT_EQ(*m.frame_of_step[0], 0u);
  EXPECT_FALSE(m.frame_of_step[1]);
  EXPECT_EQ(*m.frame_of_step[2], 1u);
  // Two files for three steps with nothing to tell them apart: ambiguous.
  options.arrival_timeout_ns = 0;
  std::vector<ShotTiming> late = {{0, 0, steps[2].trigger_ns + 400 * kMs},
                                  {0, 0, steps[2].trigger_ns + 500 * kMs}};
  const ShotMatch unsure = match_shots(steps, late, options);
  EXPECT_TRUE(unsure.ambiguous);
  EXPECT_EQ(unsure.dropped(), 3u);
}

TEST(ShotMatcher, SecondStampsStillMatchAFullBatchInOrder) {
  // No SubSec: stamps to the second cannot tell steps 200 ms apart, but a full batch is unambiguous.
  const auto steps = steps_of(5);
  auto files = files_of(steps, {0, 1, 2, 3, 4}, 12'345 * kMs);
  for (auto& f : files) {
    f.stamp_ns = f.stamp_ns / 1'000'000'000 * 1'000'000'000;
    f.resolution_ns = 1'000'000'000;
  }
  const ShotMatch m = match_shots(steps, files, kOptions);
  EXPECT_FALSE(m.ambiguous);
  EXPECT_EQ(m.dropped(), 0u);
  for (std::size_t s = 0; s < 5; ++s) EXPECT_EQ(*m.frame_of_step[s], s);
}

}  // namespace
}  // namespace lightstage
