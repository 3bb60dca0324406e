// The capture runner against a scripted controller and camera in this process
// (capture_fakes.hpp).
#include "lightstage/host/capture/capture_runner.hpp"

#include "capture_fakes.hpp"
#include "lightstage/testing/errors.hpp"

#include <gtest/gtest.h>

#include <map>

namespace lightstage {
namespace {

using testing::Bench;
using testing::Dome;

int value_of(const Taken& taken) { return taken.frame.image.at<std::uint16_t>(0, 0); }

TEST(CaptureRunner, ResolvesLoopAndTriggerAndStartsTheCameraForIt) {
  Bench bench;
  CaptureOptions options;
  options.gain = 1.5;
  CaptureRunner runner(*bench.client, bench.cam, options);
  EXPECT_FALSE(runner.closed_loop());  // auto, and no strobe input
  EXPECT_FALSE(runner.hardware_trigger());
  runner.start();
  EXPECT_EQ(bench.cam.trigger_mode, camera::TriggerMode::kSoftware);
  EXPECT_TRUE(bench.cam.streaming());
  EXPECT_DOUBLE_EQ(runner.gain(), 1.5);
  runner.stop();
  EXPECT_FALSE(bench.cam.streaming());

  options.loop = "closed";
  EXPECT_NE(testing::error_of([&] {
              CaptureRunner closed(*bench.client, bench.cam, options);
            }).find("no strobe input"),
            std::string::npos);
}

TEST(CaptureRunner, ADroppedFrameIsRetakenAndLandsAtItsShot) {
  Bench bench;
  bench.cam.drop = {1};
  CaptureOptions options;
  CaptureRunner runner(*bench.client, bench.cam, options);
  runner.start();
  const Batch batch = runner.run_batch({{4, 1000}, {5, 1000}, {6, 1000}});
  ASSERT_EQ(batch.taken.size(), 3u);
  EXPECT_EQ(batch.retakes, 1u);
  EXPECT_EQ(value_of(batch.taken.at(0)), 4);
  EXPECT_EQ(value_of(batch.taken.at(1)), 5);
  EXPECT_EQ(value_of(batch.taken.at(2)), 6);
  EXPECT_EQ(bench.cam.triggers, 4);
  EXPECT_EQ(bench.dome.lit, -1);  // dark again after each shot
}

TEST(CaptureRunner, AShotWithoutAFrameAfterItsRetakesIsAnErrorNamingTheCameraAndLed) {
  Bench bench;
  bench.cam.drop_all = true;
  CaptureOptions options;
  options.max_retakes = 2;
  CaptureRunner runner(*bench.client, bench.cam, options);
  runner.start();
  try {
    runner.run_batch({{5, 1000}});
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    ADD_FAILURE() << "a device failure, not bad input: " << e.what();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "fake:cam: no frame for LED 5 after 2 retakes");
  }
  EXPECT_EQ(bench.cam.triggers, 3);
}

TEST(CaptureRunner, SingleExposuresAreTakenExposureByExposureInPlanOrderSkippingDoneFrames) {
  Bench bench(/*max_steps=*/2);
  bench.cam.drop = {0};
  CaptureOptions options;
  CaptureRunner runner(*bench.client, bench.cam, options);
  runner.start();
  const CapturePlan plan = make_plan({4, 5, 6, 7}, {{4, 2000}, {5, 500}, {6, 2000}, {7, 2000}}, {}, {}, 0);
  std::vector<std::pair<std::size_t, int>> handed;  // (frame, LED lit in its image)
  runner.take_frames(plan, {false, false, true, false}, [&](std::size_t frame, std::vector<Take>& takes) {
    ASSERT_EQ(takes.size(), 1u);
    EXPECT_EQ(takes[0].exposure, plan.frames[frame].exposure);
    handed.emplace_back(frame, value_of(takes[0].taken));
  });
  EXPECT_EQ(handed, (std::vector<std::pair<std::size_t, int>>{{1, 5}, {0, 4}, {3, 7}}));
  EXPECT_EQ(bench.cam.shots, (std::vector<std::pair<int, double>>{{5, 500}, {5, 500}, {4, 2000}, {7, 2000}}));
  EXPECT_EQ(runner.stats().retakes, 1u);
}

TEST(CaptureRunner, BracketsAreTakenGroupByGroupEachAtItsExposuresShortestFirst) {
  Bench bench(/*max_steps=*/2);
  CaptureOptions options;
  CaptureRunner runner(*bench.client, bench.cam, options);
  runner.start();
  const CapturePlan plan = make_plan({4, 5, 6}, {{4, 1000}, {5, 1000}, {6, 1000}},
                                     {{4, {125, 1000}}, {5, {125, 1000}}, {6, {250, 1000}}}, {-3, 0}, 0);
  std::vector<std::size_t> handed;
  runner.take_frames(plan, {}, [&](std::size_t frame, std::vector<Take>& takes) {
    handed.push_back(frame);
    ASSERT_EQ(takes.size(), 2u);
    EXPECT_EQ(takes[0].exposure, plan.frames[frame].bracket[0]);
    EXPECT_EQ(takes[1].exposure, plan.frames[frame].bracket[1]);
    for (const Take& take : takes) EXPECT_EQ(value_of(take.taken), plan.frames[frame].led_id);
  });
  EXPECT_EQ(handed, (std::vector<std::size_t>{0, 1, 2}));
  EXPECT_EQ(bench.cam.shots, (std::vector<std::pair<int, double>>{
                                 {4, 125}, {5, 125}, {4, 1000}, {5, 1000}, {6, 250}, {6, 1000}}));
}

// A stop asked for while a group's brackets are being taken waits for its
// last exposure: the group is handed on whole, then the capture stops.
TEST(CaptureRunner, AStopWithinABracketGroupEndsTheGroupFirst) {
  Bench bench(/*max_steps=*/2);
  CaptureOptions options;
  // Asked for as soon as the first exposure was taken, mid-way through the first group.
  options.stop_requested = [&] { return !bench.cam.shots.empty(); };
  CaptureRunner runner(*bench.client, bench.cam, options);
  runner.start();
  const CapturePlan plan = make_plan({4, 5, 6}, {{4, 1000}, {5, 1000}, {6, 1000}},
                                     {{4, {125, 1000}}, {5, {125, 1000}}, {6, {250, 1000}}}, {-3, 0}, 0);
  std::vector<std::size_t> handed;
  EXPECT_THROW(runner.take_frames(plan, {},
                                  [&](std::size_t frame, std::vector<Take>& takes) {
                                    handed.push_back(frame);
                                    EXPECT_EQ(takes.size(), 2u);
                                  }),
               CaptureStopped);
  EXPECT_EQ(handed, (std::vector<std::size_t>{0, 1}));
  EXPECT_EQ(bench.cam.shots, (std::vector<std::pair<int, double>>{{4, 125}, {5, 125}, {4, 1000}, {5, 1000}}));
}

// A halt (the dome darkened) does not wait for the group: no LED is lit after it.
TEST(CaptureRunner, AHaltStopsWithinABracketGroupAndLightsNoLedAfterIt) {
  Bench bench(/*max_steps=*/2);
  CaptureOptions options;
  options.halt_requested = [&] { return bench.cam.shots.size() >= 1; };
  CaptureRunner runner(*bench.client, bench.cam, options);
  runner.start();
  const CapturePlan plan = make_plan({4, 5, 6}, {{4, 1000}, {5, 1000}, {6, 1000}},
                                     {{4, {125, 1000}}, {5, {125, 1000}}, {6, {250, 1000}}}, {-3, 0}, 0);
  std::vector<std::size_t> handed;
  EXPECT_THROW(
      runner.take_frames(plan, {}, [&](std::size_t frame, std::vector<Take>&) { handed.push_back(frame); }),
      CaptureStopped);
  EXPECT_TRUE(handed.empty()) << "no LED's bracket was complete";
  EXPECT_EQ(bench.cam.shots, (std::vector<std::pair<int, double>>{{4, 125}}));
}

// Without brackets, the frames taken before a halt are handed on; the batch lights no further LED.
TEST(CaptureRunner, AHaltMidBatchKeepsTheFramesTakenAndLightsNoMore) {
  Bench bench(/*max_steps=*/4);
  CaptureOptions options;
  options.halt_requested = [&] { return bench.cam.shots.size() >= 2; };
  CaptureRunner runner(*bench.client, bench.cam, options);
  runner.start();
  const CapturePlan plan = make_plan({4, 5, 6, 7}, {{4, 1000}, {5, 1000}, {6, 1000}, {7, 1000}}, {}, {}, 0);
  std::vector<std::pair<std::size_t, int>> handed;
  EXPECT_THROW(runner.take_frames(plan, {},
                                  [&](std::size_t frame, std::vector<Take>& takes) {
                                    handed.emplace_back(frame, value_of(takes[0].taken));
                                  }),
               CaptureStopped);
  EXPECT_EQ(handed, (std::vector<std::pair<std::size_t, int>>{{0, 4}, {1, 5}}));
  EXPECT_EQ(bench.cam.shots.size(), 2u);
}

TEST(CaptureRunner, FramesExposedBeforeAWatchdogAbortAreHandedOnThenTheAbortIsThrown) {
  Bench bench;
  bench.cam.hardware = true;
  bench.dome.watchdog_sequence = 0;
  bench.dome.watchdog_after = 6;  // 6 of the 12 steps exposed
  CaptureOptions options;
  CaptureRunner runner(*bench.client, bench.cam, options);
  ASSERT_TRUE(runner.hardware_trigger());
  runner.start();
  std::vector<int> ids;
  std::map<int, double> exposure;
  for (int id = 1; id <= 12; ++id) {
    ids.push_back(id);
    exposure[id] = 1000;
  }
  const CapturePlan plan = make_plan(ids, exposure, {}, {}, 0);
  std::vector<std::pair<std::size_t, int>> handed;  // (frame, LED lit in its image)
  std::string message;
  try {
    runner.take_frames(plan, {}, [&](std::size_t frame, std::vector<Take>& takes) {
      ASSERT_EQ(takes.size(), 1u);
      handed.emplace_back(frame, value_of(takes[0].taken));
    });
    ADD_FAILURE() << "the abort went unnoticed";
  } catch (const BatchAborted& e) {
    message = e.what();
  }
  EXPECT_NE(message.find("WATCHDOG after 6 of 12 steps"), std::string::npos) << message;
  EXPECT_EQ(handed,
            (std::vector<std::pair<std::size_t, int>>{{0, 1}, {1, 2}, {2, 3}, {3, 4}, {4, 5}, {5, 6}}));
}

TEST(CaptureRunner, AnAbortedBracketKeepsTheLedsWhoseBracketIsComplete) {
  Bench bench;
  bench.cam.hardware = true;
  bench.dome.watchdog_sequence = 1;  // the second exposure's batch (LED 4 at 1000 us) is cut at once
  bench.dome.watchdog_after = 0;
  CaptureOptions options;
  CaptureRunner runner(*bench.client, bench.cam, options);
  runner.start();
  // LED 5's bracket ends at 125 us (taken in full); LED 4's needs 1000 us as well.
  const CapturePlan plan =
      make_plan({4, 5}, {{4, 1000}, {5, 1000}}, {{4, {125, 1000}}, {5, {125}}}, {-3, 0}, 0);
  std::vector<std::size_t> handed;
  EXPECT_THROW(runner.take_frames(plan, {},
                                  [&](std::size_t frame, std::vector<Take>& takes) {
                                    handed.push_back(frame);
                                    EXPECT_EQ(takes.size(), plan.frames[frame].bracket.size());
                                  }),
               BatchAborted);
  EXPECT_EQ(handed, (std::vector<std::size_t>{1}));
}

TEST(CaptureRunner, AClosedLoopStepWaitsForTheStrobeNoLongerThanItsLedMayBeLit) {
  proto::Led led;
  led.set_id(4);
  led.set_max_on_us(100'000);
  Bench bench(12, {led}, /*strobe=*/true);
  bench.cam.hardware = true;
  CaptureOptions options;
  CaptureRunner runner(*bench.client, bench.cam, options);
  ASSERT_TRUE(runner.closed_loop());
  runner.start();
  const Batch batch = runner.run_batch({{4, 90'000}, {-1, 90'000}});
  EXPECT_EQ(batch.taken.size(), 2u);
  const std::lock_guard lock(bench.dome.mutex);
  ASSERT_EQ(bench.dome.uploaded.size(), 1u);
  const proto::Step& lit = bench.dome.uploaded[0].steps(0);
  ASSERT_TRUE(lit.wait_strobe());
  // The controller counts settle plus the whole timeout against the limit.
  EXPECT_LE(lit.settle_us() + lit.strobe_timeout_us(), 100'000u);
  EXPECT_GE(lit.strobe_timeout_us(), lit.exposure_us());
  // A dark step lights nothing: it may wait longer for a late camera.
  EXPECT_GT(bench.dome.uploaded[0].steps(1).strobe_timeout_us(), lit.strobe_timeout_us());
}

}  // namespace
}  // namespace lightstage
