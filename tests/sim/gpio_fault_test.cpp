// Fault injection in the chip model: parsing, lost strobes, stuck lines.
// (drop-connection acts on connections: gpio_client_server_test.cpp.)
#include "gpio_test_support.hpp"
#include "lightstage/sim/gpio/fault.hpp"
#include "lightstage/sim/gpio/virtual_chip.hpp"
#include "lightstage/testing/errors.hpp"

#include <gtest/gtest.h>

namespace lightstage::sim::gpio {
namespace {

using lightstage::testing::error_of;
using testing::entries_for;
using testing::shipped_rig;

TEST(FaultParse, AcceptsTheThreeKinds) {
  const Fault lose = parse_fault("lose-strobe:3");
  EXPECT_EQ(lose.kind, Fault::Kind::kLoseStrobe);
  EXPECT_EQ(lose.count, 3);
  const Fault stuck = parse_fault("stuck:LED5");
  EXPECT_EQ(stuck.kind, Fault::Kind::kStuck);
  EXPECT_EQ(stuck.line, "LED5");
  const Fault drop = parse_fault("drop-connection:40");
  EXPECT_EQ(drop.kind, Fault::Kind::kDropConnection);
  EXPECT_EQ(drop.count, 40);
}

TEST(FaultParse, RejectsWithTheTextAndTheForms) {
  EXPECT_NE(error_of([] { parse_fault("melt:1"); }).find("lose-strobe:N"), std::string::npos);
  EXPECT_NE(error_of([] { parse_fault("melt:1"); }).find("'melt'"), std::string::npos);
  EXPECT_NE(error_of([] { parse_fault("lose-strobe:0"); }).find("'0'"), std::string::npos);
  EXPECT_NE(error_of([] { parse_fault("lose-strobe"); }).find("lose-strobe"), std::string::npos);
  EXPECT_NE(error_of([] { parse_fault("drop-connection:x"); }).find("'x'"), std::string::npos);
  EXPECT_NE(error_of([] { parse_fault("stuck:"); }).find("stuck:LED5"), std::string::npos);
}

class ChipFaults : public ::testing::Test {
 protected:
  ChipFaults() {
    VirtualChipOptions options = chip_options_for(rig);
    options.strobe_delay_ns = 10;
    options.strobe_exposure_ns = 100;
    chip = std::make_unique<VirtualChip>(layout_from_rig(rig), options);
    firmware = chip->connect();
  }
  Rig rig = shipped_rig("sim-dome");
  std::unique_ptr<VirtualChip> chip;
  ClientId firmware = 0;
};

TEST_F(ChipFaults, LoseStrobeSkipsExactlyTheNthTrigger) {
  chip->inject(parse_fault("lose-strobe:2"));
  const std::vector<unsigned> trigger = {100};
  const std::vector<int> on = {1};
  const std::vector<int> off = {0};
  chip->request_lines(firmware, trigger, true, "fw", {}, {}, 1);
  std::vector<std::int64_t> starts;
  for (int i = 0; i < 3; ++i) {
    const std::int64_t t = 1000 * (i + 1);
    chip->set_values(firmware, trigger, on, t);
    chip->set_values(firmware, trigger, off, t + 5);
    chip->run_due(t + 500);
  }
  for (const auto& entry : entries_for(chip->timeline(), "STROBE")) {
    if (entry.value == 1) starts.push_back(entry.t_ns);
  }
  EXPECT_EQ(starts, (std::vector<std::int64_t>{1010, 3010}));
  EXPECT_EQ(chip->stats().strobes_lost, 1);
  EXPECT_EQ(chip->stats().strobes, 2);
}

TEST_F(ChipFaults, AStuckLineIgnoresSetsAndKeepsItsValue) {
  const std::vector<unsigned> leds = {4, 5};
  const std::vector<int> on = {1, 1};
  const std::vector<int> off = {0, 0};
  chip->request_lines(firmware, leds, true, "fw", {}, {}, 1);
  chip->set_values(firmware, leds, on, 10);
  chip->inject(parse_fault("stuck:LED5"));  // stuck lit
  chip->set_values(firmware, leds, off, 20);
  EXPECT_FALSE(chip->led_lit(4));
  EXPECT_TRUE(chip->led_lit(5));
  const auto led5 = entries_for(chip->timeline(), "LED5");
  ASSERT_EQ(led5.size(), 1u) << "only the change before the fault";
  EXPECT_EQ(led5[0].value, 1);
  // By offset too; dark stays dark.
  chip->inject(parse_fault("stuck:6"));
  const std::vector<unsigned> led6 = {6};
  const std::vector<int> on6 = {1};
  chip->request_lines(firmware, led6, true, "fw", {}, on6, 30);
  chip->set_values(firmware, led6, on6, 40);
  EXPECT_FALSE(chip->led_lit(6));
}

TEST_F(ChipFaults, AStuckStrobeIsADeadCameraOutput) {
  chip->inject(parse_fault("stuck:STROBE"));
  const std::vector<unsigned> trigger = {100};
  const std::vector<int> on = {1};
  chip->request_lines(firmware, trigger, true, "fw", {}, {}, 1);
  chip->set_values(firmware, trigger, on, 1000);
  EXPECT_TRUE(chip->run_due(10'000).empty());
  EXPECT_TRUE(entries_for(chip->timeline(), "STROBE").empty());
}

TEST_F(ChipFaults, UnknownLinesAndConnectionFaultsAreRefusedByTheChip) {
  const std::string error = error_of([&] { chip->inject(parse_fault("stuck:NOPE")); });
  EXPECT_NE(error.find("NOPE"), std::string::npos) << error;
  EXPECT_NE(error_of([&] { chip->inject(parse_fault("drop-connection:3")); }), "(no InputError)");
}

}  // namespace
}  // namespace lightstage::sim::gpio
