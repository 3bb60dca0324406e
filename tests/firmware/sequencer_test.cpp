#include "lightstage/firmware/sequencer.hpp"

#include "lightstage/firmware/dome_io.hpp"

#include "support/fake_chip.hpp"
#include "support/sequence_builder.hpp"
#include "support/test_rigs.hpp"
#include "support/virtual_clock.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace lightstage::firmware {
namespace {

using testing::FakeChip;
using ::testing::HasSubstr;
using testing::LineChange;
using testing::StepSpec;
using testing::VirtualClock;

constexpr unsigned kTrigger = 8;
constexpr unsigned kStrobe = 9;
constexpr std::int64_t kUs = 1000;

// The direct rig on a fake chip with a camera on the trigger, run on a virtual clock.
struct Bench {
  explicit Bench(testing::FakeCamera camera = {kTrigger, kStrobe, 50 * kUs, 500 * kUs, false},
                 Rig bench_rig = testing::direct_rig())
      : rig(std::move(bench_rig)), chip(FakeChip::with_lines(16, clock)), safety(rig) {
    chip->set_camera(camera);
    io = open_dome_io(rig, *chip, clock);
    sequencer = std::make_unique<Sequencer>(rig, *io.leds, *io.trigger, io.strobe.get(), safety, clock);
  }

  proto::SequenceDone run(const proto::Sequence& sequence, std::int64_t start_ns = 0) {
    Sequencer::Observer observer;
    observer.on_step = [this](const proto::StepEvent& event) { events.push_back(event); };
    observer.on_leds = [this](std::uint32_t, std::span<const int> leds) {
      if (on_leds) on_leds(leds);
    };
    return sequencer->run(sequence, start_ns, stop, observer);
  }

  // [on, off) intervals of one line, from the recorded changes.
  std::vector<std::pair<std::int64_t, std::int64_t>> pulses(unsigned offset) const {
    std::vector<std::pair<std::int64_t, std::int64_t>> out;
    for (const LineChange& change : chip->changes_of(offset)) {
      if (change.value == 1) out.push_back({change.t_ns, -1});
      if (change.value == 0 && !out.empty()) out.back().second = change.t_ns;
    }
    return out;
  }

  bool all_dark() const {
    for (unsigned line = 0; line < 4; ++line) {
      if (chip->value(line) != 0) return false;
    }
    return chip->value(kTrigger) == 0;
  }

  VirtualClock clock;
  Rig rig;
  std::unique_ptr<FakeChip> chip;
  DomeIo io;
  LedSafety safety;
  std::unique_ptr<Sequencer> sequencer;
  StopFlag stop;
  std::vector<proto::StepEvent> events;
  std::function<void(std::span<const int>)> on_leds;
};

TEST(Sequencer, OpenLoopLightsEachLedAroundItsTriggerAndExposure) {
  Bench bench;
  const proto::Sequence sequence = testing::one_led_per_step(
      1, {0, 1, 2, 3}, {.leds = {}, .settle_us = 200, .exposure_us = 1000, .gap_us = 1000});
  ASSERT_FALSE(bench.sequencer->check(sequence));
  const std::int64_t start = bench.clock.now_ns() + 5000 * kUs;
  const proto::SequenceDone done = bench.run(sequence, start);
  EXPECT_EQ(done.outcome(), proto::OK) << done.detail();
  EXPECT_EQ(done.steps_run(), 4u);
  ASSERT_EQ(bench.events.size(), 4u);

  const auto triggers = bench.pulses(kTrigger);
  ASSERT_EQ(triggers.size(), 4u);
  for (int i = 0; i < 4; ++i) {
    const proto::StepEvent& event = bench.events[static_cast<std::size_t>(i)];
    EXPECT_EQ(event.step(), static_cast<std::uint32_t>(i));
    EXPECT_EQ(event.tag(), 100u + static_cast<std::uint32_t>(i));
    EXPECT_THAT(event.led_ids(), ::testing::ElementsAre(i));
    EXPECT_EQ(event.outcome(), proto::OK);
    // The plan is absolute: step i starts at start + i * (settle + exposure + gap).
    EXPECT_EQ(event.planned_start_ns(), start + i * 2200 * kUs);
    EXPECT_EQ(event.lateness_ns(), 0);
    // Order on the firmware's own timestamps.
    EXPECT_LT(event.leds_on_ns(), event.trigger_ns());
    EXPECT_EQ(event.trigger_ns() - event.leds_on_ns(), 200 * kUs);
    EXPECT_EQ(event.trigger_end_ns() - event.trigger_ns(), 100 * kUs);  // the rig's pulse width
    EXPECT_GE(event.leds_off_ns(), event.trigger_ns() + 1000 * kUs);
    EXPECT_GT(event.strobe_rise_ns(), event.trigger_ns());
    // The recorded line timeline agrees, and only this step's LED was lit in its window.
    const auto pulses = bench.pulses(static_cast<unsigned>(i));
    ASSERT_EQ(pulses.size(), 1u) << "LED " << i;
    EXPECT_EQ(pulses[0].first, event.leds_on_ns());
    EXPECT_EQ(pulses[0].second, event.leds_off_ns());
    EXPECT_LT(pulses[0].first, triggers[static_cast<std::size_t>(i)].first);
    for (unsigned other = 0; other < 4; ++other) {
      if (other == static_cast<unsigned>(i)) continue;
      for (const auto& [on, off] : bench.pulses(other))
        EXPECT_TRUE(off <= event.leds_on_ns() || on >= event.leds_off_ns());
    }
  }
  EXPECT_TRUE(bench.all_dark());
}

TEST(Sequencer, ClosedLoopKeepsTheLedLitUntilTheStrobeEnds) {
  Bench bench({kTrigger, kStrobe, 80 * kUs, 3000 * kUs, false});
  const proto::Sequence sequence = testing::one_led_per_step(2, {1, 3},
                                                             {.leds = {},
                                                              .settle_us = 100,
                                                              .exposure_us = 0,
                                                              .wait_strobe = true,
                                                              .strobe_timeout_us = 8000,
                                                              .gap_us = 500});
  ASSERT_FALSE(bench.sequencer->check(sequence));
  const proto::SequenceDone done = bench.run(sequence);
  EXPECT_EQ(done.outcome(), proto::OK) << done.detail();
  ASSERT_EQ(bench.events.size(), 2u);
  for (const proto::StepEvent& event : bench.events) {
    EXPECT_EQ(event.strobe_rise_ns(), event.trigger_ns() + 80 * kUs);
    EXPECT_EQ(event.strobe_fall_ns(), event.strobe_rise_ns() + 3000 * kUs);
    EXPECT_GE(event.leds_off_ns(), event.strobe_fall_ns()) << "never dark before the exposure ends";
    EXPECT_EQ(event.lateness_ns(), 0);
  }
  // The next step is planned from the strobe edge that ended the previous one.
  EXPECT_EQ(bench.events[1].planned_start_ns(), bench.events[0].strobe_fall_ns() + 500 * kUs);
}

// A controller that wakes after the strobe timeout (a busy board) finds the camera's falling edge
// already queued with its time: within the timeout it ends the exposure, after it the step fails.
TEST(Sequencer, AStrobeThatFellInTimeCountsWhenTheControllerWakesLate) {
  const auto run = [](std::int64_t exposure_us) {
    Bench bench({kTrigger, kStrobe, 80 * kUs, exposure_us * kUs, false});
    // Every wake-up later than the whole timeout: the one after the rising edge is past it.
    bench.clock.set_oversleep(3500 * kUs);
    const proto::Sequence sequence = testing::one_led_per_step(
        7, {1},
        {.leds = {}, .settle_us = 100, .exposure_us = 0, .wait_strobe = true, .strobe_timeout_us = 3200});
    const proto::SequenceDone done = bench.run(sequence);
    EXPECT_EQ(bench.events.size(), 1u);
    EXPECT_TRUE(bench.all_dark());
    return std::pair{done, bench.events.empty() ? proto::StepEvent() : bench.events[0]};
  };
  const auto [in_time, event] = run(3000);
  EXPECT_EQ(in_time.outcome(), proto::OK) << in_time.detail();
  EXPECT_EQ(event.strobe_fall_ns(), event.trigger_ns() + 3080 * kUs);
  EXPECT_GE(event.leds_off_ns(), event.strobe_fall_ns());
  EXPECT_GT(event.lateness_ns(), 0) << "the late wake-up is reported";

  const auto [too_late, late_event] = run(3150);  // falls 30 us after the timeout
  EXPECT_EQ(too_late.outcome(), proto::STROBE_TIMEOUT);
  EXPECT_THAT(late_event.detail(), HasSubstr("no strobe"));
}

TEST(Sequencer, AMissingStrobeAbortsTheStepWithTheLedsOff) {
  Bench bench({kTrigger, kStrobe, 0, 0, /*lost=*/true});
  const proto::Sequence sequence = testing::one_led_per_step(
      3, {0, 1},
      {.leds = {}, .settle_us = 100, .exposure_us = 0, .wait_strobe = true, .strobe_timeout_us = 7000});
  const proto::SequenceDone done = bench.run(sequence);
  EXPECT_EQ(done.outcome(), proto::STROBE_TIMEOUT);
  EXPECT_EQ(done.steps_run(), 0u);
  ASSERT_EQ(bench.events.size(), 1u) << "the sequence ends at the failed step";
  const proto::StepEvent& event = bench.events[0];
  EXPECT_EQ(event.outcome(), proto::STROBE_TIMEOUT);
  EXPECT_THAT(event.detail(), HasSubstr("no strobe"));
  EXPECT_EQ(event.leds_off_ns(), event.trigger_ns() + 7000 * kUs);
  EXPECT_TRUE(bench.all_dark());
  EXPECT_TRUE(bench.pulses(1).empty()) << "the second step never ran";
}

TEST(Sequencer, LatenessIsTheWorstDeadlineOfEachStepAndDoesNotAccumulate) {
  Bench bench;
  bench.clock.set_oversleep(300 * kUs);  // every wake-up 0.3 ms late
  const proto::Sequence sequence = testing::one_led_per_step(
      4, {0, 1, 2, 3}, {.leds = {}, .settle_us = 200, .exposure_us = 1000, .gap_us = 5000});
  const std::int64_t start = bench.clock.now_ns() + 1000 * kUs;
  const proto::SequenceDone done = bench.run(sequence, start);
  ASSERT_EQ(done.outcome(), proto::OK) << done.detail();
  ASSERT_EQ(bench.events.size(), 4u);
  for (int i = 0; i < 4; ++i) {
    const proto::StepEvent& event = bench.events[static_cast<std::size_t>(i)];
    EXPECT_EQ(event.planned_start_ns(), start + i * 6200 * kUs) << "plan stays absolute";
    EXPECT_EQ(event.leds_on_ns() - event.planned_start_ns(), 300 * kUs);
    // Settle and exposure are never cut short by a late wake-up...
    EXPECT_GE(event.trigger_ns() - event.leds_on_ns(), 200 * kUs);
    EXPECT_GE(event.leds_off_ns() - event.trigger_ns(), 1000 * kUs);
    // ...so the LEDs go off 0.9 ms after plan: on +0.3, trigger +0.6, release and off +0.9.
    EXPECT_EQ(event.lateness_ns(), 900 * kUs) << "step " << i;
  }
  EXPECT_EQ(done.max_lateness_ns(), 900 * kUs);
}

TEST(Sequencer, RefusesUpFrontWhatWouldExceedTheOnTimeLimit) {
  Bench bench;
  const auto refusal =
      bench.sequencer->check(testing::make_sequence(5, {{.leds = {2}, .exposure_us = 20000}}));
  ASSERT_TRUE(refusal);
  EXPECT_EQ(refusal->code, proto::Error::SAFETY_LIMIT);
  EXPECT_THAT(refusal->message, HasSubstr("LED 2"));
  EXPECT_THAT(refusal->message, HasSubstr("max_on_us"));
  // A closed-loop step counts at its strobe timeout.
  const auto closed = bench.sequencer->check(testing::make_sequence(
      6, {{.leds = {1}, .exposure_us = 0, .wait_strobe = true, .strobe_timeout_us = 15000}}));
  ASSERT_TRUE(closed);
  EXPECT_EQ(closed->code, proto::Error::SAFETY_LIMIT);
  EXPECT_THAT(closed->message, HasSubstr("strobe timeout"));
}

TEST(Sequencer, RefusesUpFrontWhatWouldExceedTheDutyLimit) {
  Bench bench;
  // 9 ms on + 1 ms gap: duty 0.9 where 0.5 over 100 ms is allowed.
  const proto::Sequence sequence = testing::make_sequence(
      7, std::vector<StepSpec>(8, {.leds = {3}, .settle_us = 0, .exposure_us = 9000, .gap_us = 1000}));
  const auto refusal = bench.sequencer->check(sequence);
  ASSERT_TRUE(refusal);
  EXPECT_EQ(refusal->code, proto::Error::SAFETY_LIMIT);
  EXPECT_THAT(refusal->message, HasSubstr("step 5"));
  EXPECT_THAT(refusal->message, HasSubstr("max_duty"));
}

TEST(Sequencer, EnforcesTheDutyLimitAtRunTimeEvenWithoutACheck) {
  Bench bench;
  const proto::Sequence sequence = testing::make_sequence(
      8, std::vector<StepSpec>(8, {.leds = {3}, .settle_us = 0, .exposure_us = 9000, .gap_us = 1000}));
  const proto::SequenceDone done = bench.run(sequence);  // the host skipped check(): run() still refuses
  EXPECT_EQ(done.outcome(), proto::SAFETY_LIMIT);
  EXPECT_EQ(done.steps_run(), 5u);
  std::int64_t on_ns = 0;
  for (const auto& [on, off] : bench.pulses(3)) on_ns += off - on;
  EXPECT_LE(on_ns, 50'000 * kUs) << "never more than max_duty * window";
  EXPECT_TRUE(bench.all_dark());
  EXPECT_EQ(bench.events.back().outcome(), proto::SAFETY_LIMIT);
  EXPECT_EQ(bench.events.back().leds_on_ns(), 0) << "refused before lighting";
}

TEST(Sequencer, SwitchesLedsOffAtTheirOnTimeLimitWhenWakeUpsRunLate) {
  Bench bench;
  bench.clock.set_oversleep(400 * kUs);
  // 0.5 + 9.4 ms planned fits in 10 ms, but late wake-ups stretch it.
  const proto::Sequence sequence =
      testing::make_sequence(9, {{.leds = {0}, .settle_us = 500, .exposure_us = 9400}});
  ASSERT_FALSE(bench.sequencer->check(sequence));
  const proto::SequenceDone done = bench.run(sequence, bench.clock.now_ns() + 1000 * kUs);
  EXPECT_EQ(done.outcome(), proto::SAFETY_LIMIT);
  EXPECT_THAT(done.detail(), HasSubstr("on-time limit"));
  const auto pulses = bench.pulses(0);
  ASSERT_EQ(pulses.size(), 1u);
  // Off at the first wake-up after the limit (one oversleep late at most).
  EXPECT_LE(pulses[0].second - pulses[0].first, (10000 + 400) * kUs);
  EXPECT_GE(pulses[0].second - pulses[0].first, 10000 * kUs);
  EXPECT_TRUE(bench.all_dark());
}

TEST(Sequencer, RefusesBadSteps) {
  Bench bench;
  const auto unknown = bench.sequencer->check(testing::make_sequence(10, {{.leds = {7}}}));
  ASSERT_TRUE(unknown);
  EXPECT_EQ(unknown->code, proto::Error::BAD_REQUEST);
  EXPECT_THAT(unknown->message, HasSubstr("no LED 7"));

  proto::Sequence dimmed = testing::make_sequence(11, {{.leds = {1}}});
  dimmed.mutable_steps(0)->mutable_leds(0)->set_level(0.5F);
  const auto dim = bench.sequencer->check(dimmed);
  ASSERT_TRUE(dim);
  EXPECT_THAT(dim->message, HasSubstr("cannot dim"));

  EXPECT_TRUE(bench.sequencer->check(testing::make_sequence(12, {})));
}

TEST(Sequencer, StopsMidStepWithTheLedsOff) {
  Bench bench;
  bench.on_leds = [&](std::span<const int> leds) {
    if (!leds.empty() && leds[0] == 1) bench.stop.request(proto::WATCHDOG, "heartbeat lost");
  };
  const proto::SequenceDone done = bench.run(testing::one_led_per_step(13, {0, 1, 2}, {}));
  EXPECT_EQ(done.outcome(), proto::WATCHDOG);
  EXPECT_EQ(done.detail(), "heartbeat lost");
  EXPECT_EQ(done.steps_run(), 1u);
  ASSERT_EQ(bench.events.size(), 2u);
  EXPECT_EQ(bench.events[1].outcome(), proto::WATCHDOG);
  EXPECT_GT(bench.events[1].leds_off_ns(), 0);
  EXPECT_TRUE(bench.pulses(2).empty());
  EXPECT_TRUE(bench.all_dark());
}

TEST(Sequencer, DrivesAShiftRegisterChainWithLatchesOnTheDeadlines) {
  VirtualClock clock;
  const Rig rig = testing::chain_rig();
  auto chip = FakeChip::with_lines(8, clock,
                                   {{testing::kSrData, "SR_DATA"},
                                    {testing::kSrClock, "SR_CLK"},
                                    {testing::kSrLatch, "SR_LATCH"},
                                    {testing::kSrOutputEnable, "SR_OE"},
                                    {testing::kCamTrig, "CAM_TRIG"}});
  DomeIo io = open_dome_io(rig, *chip, clock);
  LedSafety safety(rig);
  Sequencer sequencer(rig, *io.leds, *io.trigger, nullptr, safety, clock);
  std::vector<proto::StepEvent> events;
  Sequencer::Observer observer;
  observer.on_step = [&](const proto::StepEvent& event) { events.push_back(event); };
  StopFlag stop;
  const std::int64_t start = clock.now_ns() + 10'000 * kUs;
  const proto::SequenceDone done = sequencer.run(
      testing::one_led_per_step(15, {104, 109, 115}, {.leds = {}, .settle_us = 100, .exposure_us = 2000}),
      start, stop, observer);
  ASSERT_EQ(done.outcome(), proto::OK) << done.detail();
  ASSERT_EQ(events.size(), 3u);
  // Replay the 74HC595: the latched outputs at each latch edge, in time order.
  std::vector<int> shift(16, 0);
  int data = 0;
  std::vector<std::pair<std::int64_t, std::vector<int>>> latched;
  for (const LineChange& change : chip->changes()) {
    if (change.offset == testing::kSrData) data = change.value;
    if (change.offset == testing::kSrClock && change.value == 1) {
      for (std::size_t i = 15; i > 0; --i) shift[i] = shift[i - 1];
      shift[0] = data;
    }
    if (change.offset == testing::kSrLatch && change.value == 1) latched.push_back({change.t_ns, shift});
  }
  for (std::size_t i = 0; i < 3; ++i) {
    const proto::StepEvent& event = events[i];
    const int bit = static_cast<int>(event.led_ids(0)) - 100;
    EXPECT_EQ(event.leds_on_ns(), event.planned_start_ns())
        << "staged ahead: the latch lands on the deadline";
    EXPECT_EQ(event.lateness_ns(), 0);
    const auto on = std::find_if(latched.begin(), latched.end(),
                                 [&](const auto& l) { return l.first == event.leds_on_ns(); });
    ASSERT_NE(on, latched.end());
    std::vector<int> expected(16, 0);
    expected[static_cast<std::size_t>(bit)] = 1;
    EXPECT_EQ(on->second, expected) << "step " << i;
    const auto off = std::find_if(latched.begin(), latched.end(),
                                  [&](const auto& l) { return l.first == event.leds_off_ns(); });
    ASSERT_NE(off, latched.end());
    EXPECT_EQ(off->second, std::vector<int>(16, 0));
    EXPECT_LT(event.leds_on_ns(), event.trigger_ns());
    EXPECT_GE(event.leds_off_ns(), event.trigger_ns() + 2000 * kUs);
  }
}

TEST(Sequencer, AGpioFailureEndsTheSequenceWithoutThrowing) {
  Bench bench;
  bench.chip->fail_after_sets(3);
  proto::SequenceDone done;
  EXPECT_NO_THROW(done = bench.run(testing::one_led_per_step(14, {0, 1, 2}, {})));
  EXPECT_EQ(done.outcome(), proto::GPIO_ERROR);
  EXPECT_THAT(done.detail(), HasSubstr("injected failure"));
}

constexpr unsigned kFocus = 10;

TEST(Sequencer, AStillsCameraGetsItsHalfPressLeadAndTheLedCoversItsShutterLag) {
  Bench bench({kTrigger, 11, 0, 0, true}, testing::dslr_rig());
  const proto::Sequence sequence = testing::one_led_per_step(
      1, {0, 1}, {.leds = {}, .settle_us = 500, .exposure_us = 10000, .gap_us = 1000});
  ASSERT_FALSE(bench.sequencer->check(sequence));
  const proto::SequenceDone done = bench.run(sequence, bench.clock.now_ns() + 1000 * kUs);
  ASSERT_EQ(done.outcome(), proto::OK) << done.detail();
  const auto shutter = bench.pulses(kTrigger), focus = bench.pulses(kFocus);
  ASSERT_EQ(shutter.size(), 2u);
  ASSERT_EQ(focus.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    const proto::StepEvent& event = bench.events[i];
    // Half-press with the LED, the shutter its lead later (longer than settle_us), both released together.
    EXPECT_EQ(focus[i].first, event.leds_on_ns());
    EXPECT_EQ(shutter[i].first - focus[i].first, 20000 * kUs);
    EXPECT_EQ(shutter[i].second - shutter[i].first, 50000 * kUs);
    EXPECT_EQ(focus[i].second, shutter[i].second);
    // Lit through the lag and the exposure, whenever within the lag the camera starts.
    EXPECT_EQ(event.leds_off_ns() - event.trigger_ns(), (30000 + 10000) * kUs);
  }
  EXPECT_LE(focus[0].second, focus[1].first);
  EXPECT_TRUE(bench.all_dark());
  EXPECT_EQ(bench.chip->value(kFocus), 0);
  // The lead and the lag count against the LED's on-time: 20 + 30 + 10 ms over a 55 ms limit is refused.
  Bench tight({kTrigger, 11, 0, 0, true}, testing::dslr_rig(55000));
  const auto refusal = tight.sequencer->check(sequence);
  ASSERT_TRUE(refusal);
  EXPECT_EQ(refusal->code, proto::Error::SAFETY_LIMIT);
  EXPECT_DOUBLE_EQ(tight.sequencer->worst_case_on_us(sequence.steps(0)), 20000 + 30000 + 10000);
}

}  // namespace
}  // namespace lightstage::firmware
