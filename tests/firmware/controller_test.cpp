#include "lightstage/firmware/controller.hpp"

#include "support/fake_chip.hpp"
#include "support/message_log.hpp"
#include "support/sequence_builder.hpp"
#include "support/test_rigs.hpp"
#include "support/virtual_clock.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>

namespace lightstage::firmware {
namespace {

using ::testing::ElementsAre;
using testing::FakeChip;
using ::testing::HasSubstr;
using testing::ManualClock;
using testing::MessageLog;
using testing::VirtualClock;

constexpr std::int64_t kMs = 1'000'000;

proto::SetLeds leds(std::initializer_list<int> ids) {
  proto::SetLeds request;
  for (const int id : ids) {
    proto::LedLevel& level = *request.add_leds();
    level.set_led_id(static_cast<std::uint32_t>(id));
    level.set_level(1.0F);
  }
  return request;
}

bool is_fault(const proto::ControllerMessage& message) { return message.has_fault(); }

// The direct rig (10 ms on-time, duty 0.5 over 100 ms) on a fake chip.
template <typename ClockType>
struct Bench {
  explicit Bench(ControllerOptions options = {})
      : rig(testing::direct_rig()), chip(FakeChip::with_lines(16, clock)) {
    controller = std::make_unique<Controller>(rig, open_dome_io(rig, *chip, clock), clock, options);
    controller->set_sink(log.sink());
  }
  ~Bench() { controller.reset(); }

  std::int64_t on_time_ns(unsigned line) const {
    std::int64_t total = 0;
    std::int64_t since = -1;
    for (const auto& change : chip->changes_of(line)) {
      if (change.value == 1) since = change.t_ns;
      if (change.value == 0 && since >= 0) total += change.t_ns - since;
    }
    return total;
  }

  ClockType clock;
  Rig rig;
  std::unique_ptr<FakeChip> chip;
  MessageLog log;
  std::unique_ptr<Controller> controller;
};

TEST(Controller, SwitchesAStaticLedOffAtItsOnTimeLimitAndReportsAFault) {
  Bench<VirtualClock> bench;
  ASSERT_FALSE(bench.controller->set_leds(leds({0})));
  // (On the virtual clock the hold's worker reaches the limit at once.)
  const auto fault = bench.log.wait_for(is_fault);
  ASSERT_TRUE(fault) << "the LED was never switched off";
  EXPECT_EQ(fault->fault().outcome(), proto::SAFETY_LIMIT);
  EXPECT_THAT(fault->fault().led_ids(), ElementsAre(0u));
  EXPECT_THAT(fault->fault().detail(), HasSubstr("max_on_us 10000"));
  EXPECT_EQ(bench.chip->value(0), 0);
  EXPECT_EQ(bench.on_time_ns(0), 10 * kMs) << "exactly the limit on the virtual clock";
  EXPECT_EQ(bench.controller->status().state(), proto::Status::FAULT);
  EXPECT_FALSE(bench.controller->active());
  bench.controller->clear_fault();
  EXPECT_EQ(bench.controller->status().state(), proto::Status::IDLE);
}

TEST(Controller, RefusesAStaticLedWhoseDutyBudgetIsSpent) {
  Bench<VirtualClock> bench;
  // Five 10 ms holds use the 50 ms budget of the 100 ms window.
  for (int i = 0; i < 5; ++i) {
    ASSERT_FALSE(bench.controller->set_leds(leds({3}))) << i;
    ASSERT_TRUE(bench.log.wait_count(is_fault, static_cast<std::size_t>(i) + 1));
  }
  const auto refusal = bench.controller->set_leds(leds({3}));
  ASSERT_TRUE(refusal);
  EXPECT_EQ(refusal->code, proto::Error::SAFETY_LIMIT);
  EXPECT_THAT(refusal->message, HasSubstr("duty budget"));
  EXPECT_EQ(bench.chip->value(3), 0);
  EXPECT_LE(bench.on_time_ns(3), 50 * kMs);
}

TEST(Controller, KeepsCountingTheOnTimeOfAnLedThatStaysLit) {
  Bench<ManualClock> bench;
  ASSERT_FALSE(bench.controller->set_leds(leds({0})));
  EXPECT_TRUE(bench.controller->active()) << "a lit LED is what the watchdog guards";
  bench.clock.advance(6 * kMs);
  ASSERT_FALSE(bench.controller->set_leds(leds({0, 1})));  // LED 0 stays lit: its 10 ms keep running
  EXPECT_EQ(bench.chip->changes_of(0).size(), 1u) << "no glitch on the LED that stays lit";
  bench.clock.advance(5 * kMs);
  const auto fault = bench.log.wait_for(is_fault);
  ASSERT_TRUE(fault);
  EXPECT_THAT(fault->fault().led_ids(), ElementsAre(0u));
  EXPECT_EQ(bench.chip->value(0), 0);
  EXPECT_EQ(bench.chip->value(1), 1) << "LED 1 has time left";
  EXPECT_THAT(bench.controller->status().leds_on(), ElementsAre(1u));

  bench.controller->stop(proto::WATCHDOG, "watchdog: host silent");
  EXPECT_EQ(bench.chip->value(1), 0);
  const auto messages = bench.log.messages();
  ASSERT_EQ(std::count_if(messages.begin(), messages.end(), is_fault), 2);
  EXPECT_EQ(messages.back().fault().outcome(), proto::WATCHDOG);
  EXPECT_THAT(messages.back().fault().led_ids(), ElementsAre(1u));
  EXPECT_EQ(bench.controller->status().state(), proto::Status::FAULT);
}

TEST(Controller, RunsASequenceAndReportsEveryStepThenDone) {
  Bench<VirtualClock> bench;
  const proto::Sequence sequence = testing::one_led_per_step(5, {0, 1, 2, 3}, {});
  ASSERT_FALSE(bench.controller->upload(sequence));
  bool accepted = false;
  ASSERT_FALSE(bench.controller->run(5, 0, [&] { accepted = true; }));
  EXPECT_TRUE(accepted);
  const auto done = bench.log.wait_for([](const auto& m) { return m.has_sequence_done(); });
  ASSERT_TRUE(done);
  EXPECT_EQ(done->sequence_done().outcome(), proto::OK);
  EXPECT_EQ(done->sequence_done().steps_run(), 4u);
  const auto messages = bench.log.messages();
  ASSERT_EQ(messages.size(), 5u);
  for (std::uint32_t i = 0; i < 4; ++i) EXPECT_EQ(messages[i].step_event().step(), i);
  EXPECT_EQ(bench.controller->status().state(), proto::Status::IDLE);
}

TEST(Controller, RefusesAStartFarAheadOfItsClock) {
  Bench<VirtualClock> bench;
  ASSERT_FALSE(bench.controller->upload(testing::one_led_per_step(8, {0, 1}, {})));
  for (const std::int64_t start_ns :
       {std::numeric_limits<std::int64_t>::max(), bench.clock.now_ns() + Sequencer::kMaxStartAheadNs + 1}) {
    const auto refusal = bench.controller->run(8, start_ns);
    ASSERT_TRUE(refusal) << start_ns;
    EXPECT_EQ(refusal->code, proto::Error::BAD_REQUEST);
    EXPECT_THAT(refusal->message, HasSubstr("ahead of the controller's clock"));
  }
  EXPECT_FALSE(bench.controller->active());
  bool accepted = false;
  ASSERT_FALSE(bench.controller->run(8, bench.clock.now_ns() + 1'000'000, [&] { accepted = true; }));
  EXPECT_TRUE(accepted);
  const auto done = bench.log.wait_for([](const auto& m) { return m.has_sequence_done(); });
  ASSERT_TRUE(done);
  EXPECT_EQ(done->sequence_done().outcome(), proto::OK);
}

TEST(Controller, RefusesUnknownSequencesAndStaticLedsWhileRunning) {
  Bench<ManualClock> bench;
  const auto missing = bench.controller->run(77, 0);
  ASSERT_TRUE(missing);
  EXPECT_EQ(missing->code, proto::Error::NO_SUCH_SEQUENCE);

  ASSERT_FALSE(bench.controller->upload(testing::one_led_per_step(6, {2}, {})));
  ASSERT_FALSE(bench.controller->run(6, 0));  // the manual clock holds it in its first step
  EXPECT_TRUE(bench.controller->active());
  const auto busy = bench.controller->set_leds(leds({1}));
  ASSERT_TRUE(busy);
  EXPECT_EQ(busy->code, proto::Error::BUSY);
  bench.controller->stop(proto::ABORTED_BY_HOST, "aborted by the host");
  const auto done = bench.log.wait_for([](const auto& m) { return m.has_sequence_done(); });
  ASSERT_TRUE(done);
  EXPECT_EQ(done->sequence_done().outcome(), proto::ABORTED_BY_HOST);
  EXPECT_EQ(bench.controller->status().state(), proto::Status::IDLE);
  for (unsigned line = 0; line < 4; ++line) EXPECT_EQ(bench.chip->value(line), 0);
}

TEST(Controller, DarkensTheDomeWhenDestroyed) {
  Bench<ManualClock> bench;
  ASSERT_FALSE(bench.controller->set_leds(leds({1, 2})));
  EXPECT_EQ(bench.chip->value(2), 1);
  bench.controller.reset();
  EXPECT_EQ(bench.chip->value(1), 0);
  EXPECT_EQ(bench.chip->value(2), 0);
}

TEST(Controller, RefusesUnknownLedsAndDimming) {
  Bench<ManualClock> bench;
  const auto unknown = bench.controller->set_leds(leds({9}));
  ASSERT_TRUE(unknown);
  EXPECT_EQ(unknown->code, proto::Error::BAD_REQUEST);
  proto::SetLeds dim = leds({1});
  dim.mutable_leds(0)->set_level(0.25F);
  const auto dimmed = bench.controller->set_leds(dim);
  ASSERT_TRUE(dimmed);
  EXPECT_THAT(dimmed->message, HasSubstr("cannot dim"));
}

// A wake-up that comes late (a loaded machine) must not carry a static LED
// past its limit: the cut-off is planned a margin ahead. On the virtual clock
// every sleep wakes 1.5 ms late; the order of the chip's line changes shows
// the LED off before its 10 ms were up.
TEST(Controller, StaticCutOffPlannedAheadSoALateWakeUpStaysWithinTheLimit) {
  Bench<VirtualClock> bench(ControllerOptions{.cutoff_margin_us = 2000});
  bench.clock.set_oversleep(1'500'000);
  ASSERT_FALSE(bench.controller->set_leds(leds({1})));
  ASSERT_TRUE(bench.log.wait_for(is_fault)) << "the LED was never switched off";
  const auto changes = bench.chip->changes_of(1);
  ASSERT_EQ(changes.size(), 2u);
  EXPECT_EQ(changes[0].value, 1);
  EXPECT_EQ(changes[1].value, 0);
  EXPECT_LE(changes[1].t_ns - changes[0].t_ns, 10 * kMs) << "the cut-off overshot max_on_us";
  EXPECT_GE(changes[1].t_ns - changes[0].t_ns, 8 * kMs) << "switched off sooner than the margin asks";
}

// The margin never eats more than half of a short budget.
TEST(Controller, CutOffMarginIsAtMostHalfTheBudget) {
  Bench<VirtualClock> bench(ControllerOptions{.cutoff_margin_us = 50'000});
  ASSERT_FALSE(bench.controller->set_leds(leds({2})));
  ASSERT_TRUE(bench.log.wait_for(is_fault));
  EXPECT_EQ(bench.on_time_ns(2), 5 * kMs);
}

// What hosts may make the controller keep is bounded by size, and goes with
// the session that uploaded it.
TEST(Controller, StoredSequencesAreBoundedByTotalSizeAndForgotten) {
  const proto::Sequence one = testing::one_led_per_step(1, {0, 1, 2, 3}, {.leds = {}, .exposure_us = 100});
  const std::size_t bytes = one.ByteSizeLong();
  Bench<VirtualClock> bench(ControllerOptions{.max_sequence_bytes = 2 * bytes + bytes / 2});
  ASSERT_FALSE(bench.controller->upload(one));
  proto::Sequence two = one;
  two.set_id(2);
  ASSERT_FALSE(bench.controller->upload(two));
  proto::Sequence three = one;
  three.set_id(3);
  const auto refused = bench.controller->upload(three);
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->code, proto::Error::BAD_REQUEST);
  EXPECT_THAT(refused->message, HasSubstr("byte limit"));
  // Replacing a stored sequence counts its new size only.
  EXPECT_FALSE(bench.controller->upload(two));
  bench.controller->forget_sequences();
  const auto gone = bench.controller->run(1, 0);
  ASSERT_TRUE(gone);
  EXPECT_EQ(gone->code, proto::Error::NO_SUCH_SEQUENCE);
  EXPECT_FALSE(bench.controller->upload(three)) << "forgetting frees the space";
}

// A GPIO backend that failed cannot be trusted again: the fault stays in
// Status, and every command is refused, so that the daemon can exit and
// systemd restart it.
TEST(Controller, AFailedGpioBackendStaysAFaultAndRefusesCommands) {
  Bench<ManualClock> bench;
  EXPECT_FALSE(bench.controller->gpio_failure());
  bench.chip->fail_after_sets(0);
  const auto failed = bench.controller->set_leds(leds({1}));
  ASSERT_TRUE(failed);
  EXPECT_EQ(failed->code, proto::Error::GPIO_ERROR);
  ASSERT_TRUE(bench.controller->gpio_failure());
  EXPECT_EQ(bench.controller->status().state(), proto::Status::FAULT);
  EXPECT_THAT(bench.controller->status().last_fault(), HasSubstr("GPIO backend lost"));
  bench.controller->clear_fault();
  EXPECT_EQ(bench.controller->status().state(), proto::Status::FAULT) << "a new command hid the failure";
  for (const auto& refusal :
       {bench.controller->set_leds(leds({})), bench.controller->upload(testing::one_led_per_step(4, {0}, {})),
        bench.controller->run(4, 0)}) {
    ASSERT_TRUE(refusal);
    EXPECT_EQ(refusal->code, proto::Error::GPIO_ERROR);
    EXPECT_THAT(refusal->message, HasSubstr("shutting down"));
  }
}

}  // namespace
}  // namespace lightstage::firmware
