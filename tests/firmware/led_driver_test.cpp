#include "lightstage/firmware/led_driver.hpp"
#include "lightstage/firmware/direct_led_driver.hpp"
#include "lightstage/firmware/shift_register_led_driver.hpp"

#include "support/fake_chip.hpp"
#include "support/test_rigs.hpp"
#include "support/virtual_clock.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace lightstage::firmware {
namespace {

using testing::FakeChip;
using ::testing::HasSubstr;
using testing::LineChange;
using testing::VirtualClock;

// A 74HC595 chain replayed from the recorded line changes: what the outputs
// showed after each latch edge, and whether OE let them through.
struct ChainReplay {
  struct Latch {
    std::int64_t t_ns;
    std::vector<int> outputs;  // by chain bit
    bool enabled;              // OE active at the latch
  };
  std::vector<Latch> latches;
  std::int64_t first_enable_ns = -1;
  bool enabled_at_end = false;
};

ChainReplay replay_chain(const std::vector<LineChange>& changes, int length) {
  ChainReplay replay;
  std::vector<int> shift(static_cast<std::size_t>(length), 0);
  int data = 0;
  bool enabled = false;
  for (const LineChange& change : changes) {
    if (change.offset == testing::kSrData) data = change.value;
    if (change.offset == testing::kSrClock && change.value == 1) {
      // Rising clock: everything moves one register bit on, DS enters bit 0.
      for (std::size_t i = shift.size() - 1; i > 0; --i) shift[i] = shift[i - 1];
      shift[0] = data;
    }
    if (change.offset == testing::kSrLatch && change.value == 1)
      replay.latches.push_back({change.t_ns, shift, enabled});
    if (change.offset == testing::kSrOutputEnable) {
      enabled = change.value == 1;
      if (enabled && replay.first_enable_ns < 0) replay.first_enable_ns = change.t_ns;
    }
  }
  replay.enabled_at_end = enabled;
  return replay;
}

std::unique_ptr<FakeChip> chain_chip(VirtualClock& clock) {
  return FakeChip::with_lines(8, clock,
                              {{testing::kSrData, "SR_DATA"},
                               {testing::kSrClock, "SR_CLK"},
                               {testing::kSrLatch, "SR_LATCH"},
                               {testing::kSrOutputEnable, "SR_OE"},
                               {testing::kCamTrig, "CAM_TRIG"}});
}

TEST(DirectLedDriver, LightsExactlyTheGivenLedsInOneSetStampedByTheCaller) {
  VirtualClock clock;
  const Rig rig = testing::direct_rig();
  auto chip = FakeChip::with_lines(16, clock);
  DirectLedDriver driver(rig, *chip, chip->info());
  EXPECT_EQ(chip->consumer(0), "lightstage-domed");
  EXPECT_TRUE(chip->active_low(2));
  EXPECT_FALSE(chip->active_low(1));
  EXPECT_TRUE(chip->changes().empty()) << "requested dark, no glitch";

  EXPECT_EQ(driver.show(std::vector<int>{1, 2}, 5000), 5000);
  EXPECT_EQ(chip->value(0), 0);
  EXPECT_EQ(chip->value(1), 1);
  EXPECT_EQ(chip->value(2), 1);  // logical: the backend applies active-low
  for (const LineChange& change : chip->changes()) EXPECT_EQ(change.t_ns, 5000);

  driver.show(std::vector<int>{3}, 6000);
  EXPECT_EQ(chip->value(1), 0);
  EXPECT_EQ(chip->value(2), 0);
  EXPECT_EQ(chip->value(3), 1);
  driver.all_off(7000);
  for (unsigned line = 0; line < 4; ++line) EXPECT_EQ(chip->value(line), 0) << line;

  EXPECT_THROW(driver.show(std::vector<int>{42}, 8000), gpio::GpioError);
}

TEST(DirectLedDriver, ReleasesItsLinesWhenDestroyed) {
  VirtualClock clock;
  const Rig rig = testing::direct_rig();
  auto chip = FakeChip::with_lines(16, clock);
  { DirectLedDriver driver(rig, *chip, chip->info()); }
  EXPECT_EQ(chip->consumer(0), "");
}

TEST(ShiftRegisterLedDriver, ClearsTheChainBeforeEnablingOutputs) {
  VirtualClock clock;
  const Rig rig = testing::chain_rig();
  auto chip = chain_chip(clock);
  ShiftRegisterLedDriver driver(rig, rig.chains.front(), *chip, chip->info(), clock);
  EXPECT_TRUE(chip->active_low(testing::kSrOutputEnable));
  const ChainReplay replay = replay_chain(chip->changes(), 16);
  ASSERT_EQ(replay.latches.size(), 1u);
  EXPECT_EQ(replay.latches[0].outputs, std::vector<int>(16, 0));
  EXPECT_FALSE(replay.latches[0].enabled) << "OE must stay inactive until the chain holds zeros";
  EXPECT_GT(replay.first_enable_ns, replay.latches[0].t_ns);
  EXPECT_TRUE(replay.enabled_at_end);
}

TEST(ShiftRegisterLedDriver, LatchesExactlyTheLitLedsAtTheirBits) {
  VirtualClock clock;
  const Rig rig = testing::chain_rig();
  auto chip = chain_chip(clock);
  ShiftRegisterLedDriver driver(rig, rig.chains.front(), *chip, chip->info(), clock);
  const std::int64_t latched_ns = driver.show(std::vector<int>{100, 103, 115}, clock.now_ns());

  const ChainReplay replay = replay_chain(chip->changes(), 16);
  ASSERT_EQ(replay.latches.size(), 2u);
  std::vector<int> expected(16, 0);
  expected[0] = expected[3] = expected[15] = 1;
  EXPECT_EQ(replay.latches[1].outputs, expected);
  EXPECT_TRUE(replay.latches[1].enabled);
  EXPECT_EQ(replay.latches[1].t_ns, latched_ns) << "show() reports the latch edge";

  // Every change is at least half a clock period (0.25 us) after the previous one.
  const auto changes = chip->changes();
  for (std::size_t i = 1; i < changes.size(); ++i) {
    if (changes[i].t_ns != changes[i - 1].t_ns) {
      EXPECT_GE(changes[i].t_ns - changes[i - 1].t_ns, 250);
    }
  }

  driver.show(std::vector<int>{107}, clock.now_ns());
  const ChainReplay after = replay_chain(chip->changes(), 16);
  std::vector<int> only_seven(16, 0);
  only_seven[7] = 1;
  EXPECT_EQ(after.latches.back().outputs, only_seven);
  EXPECT_THROW(driver.show(std::vector<int>{0}, clock.now_ns()), gpio::GpioError);
}

TEST(ShiftRegisterLedDriver, StagingShiftsWithoutChangingTheLedsUntilCommit) {
  VirtualClock clock;
  const Rig rig = testing::chain_rig();
  auto chip = chain_chip(clock);
  ShiftRegisterLedDriver driver(rig, rig.chains.front(), *chip, chip->info(), clock);
  driver.show(std::vector<int>{105}, clock.now_ns());
  driver.stage(std::vector<int>{106});
  const ChainReplay staged = replay_chain(chip->changes(), 16);
  ASSERT_EQ(staged.latches.size(), 2u) << "staging must not latch";
  EXPECT_EQ(staged.latches.back().outputs[5], 1);
  const std::int64_t deadline = clock.now_ns() + 1'000'000;
  EXPECT_EQ(driver.commit(deadline), deadline) << "the latch edge lands on the deadline";
  const ChainReplay committed = replay_chain(chip->changes(), 16);
  std::vector<int> only_six(16, 0);
  only_six[6] = 1;
  EXPECT_EQ(committed.latches.back().outputs, only_six);
}

TEST(ShiftRegisterLedDriver, ClearsTheChainAndDisablesOutputsWhenDestroyed) {
  VirtualClock clock;
  const Rig rig = testing::chain_rig();
  auto chip = chain_chip(clock);
  {
    ShiftRegisterLedDriver driver(rig, rig.chains.front(), *chip, chip->info(), clock);
    driver.show(std::vector<int>{101, 102}, clock.now_ns());
  }
  const ChainReplay replay = replay_chain(chip->changes(), 16);
  EXPECT_EQ(replay.latches.back().outputs, std::vector<int>(16, 0));
  EXPECT_FALSE(replay.enabled_at_end);
  EXPECT_EQ(chip->consumer(testing::kSrData), "");
}

TEST(MakeLedDriver, ChoosesTheDriverFromTheRig) {
  VirtualClock clock;
  const Rig direct = testing::direct_rig();
  auto direct_chip = FakeChip::with_lines(16, clock);
  EXPECT_THAT(make_led_driver(direct, *direct_chip, clock)->describe(), HasSubstr("direct lines"));

  const Rig chain = testing::chain_rig();
  auto chip = chain_chip(clock);
  auto driver = make_led_driver(chain, *chip, clock);
  EXPECT_THAT(driver->describe(), HasSubstr("shift-register chain 'leds'"));
  EXPECT_TRUE(driver->carries(115));
  EXPECT_FALSE(driver->carries(0));
}

TEST(MakeLedDriver, NamesTheRigLineTheChipLacks) {
  VirtualClock clock;
  const Rig rig = testing::chain_rig();
  auto chip = FakeChip::with_lines(8, clock, {{0, "SR_DATA"}, {1, "SR_CLK"}, {3, "SR_OE"}});
  try {
    make_led_driver(rig, *chip, clock);
    FAIL() << "expected a GpioError";
  } catch (const gpio::GpioError& e) {
    EXPECT_THAT(e.what(), HasSubstr("chain-16.yaml"));
    EXPECT_THAT(e.what(), HasSubstr("\"SR_LATCH\""));
    EXPECT_THAT(e.what(), HasSubstr("latch"));
  }
}

TEST(MakeLedDriver, RefusesABusyLine) {
  VirtualClock clock;
  const Rig rig = testing::direct_rig();
  auto chip = FakeChip::with_lines(16, clock);
  chip->occupy(3, "someone-else");
  try {
    make_led_driver(rig, *chip, clock);
    FAIL() << "expected a GpioError";
  } catch (const gpio::GpioError& e) {
    EXPECT_THAT(e.what(), HasSubstr("busy"));
    EXPECT_THAT(e.what(), HasSubstr("someone-else"));
  }
  EXPECT_EQ(chip->consumer(0), "") << "a failed request leaves nothing claimed";
}

}  // namespace
}  // namespace lightstage::firmware
