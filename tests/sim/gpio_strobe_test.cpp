// The emulated camera strobe: scheduled from the trigger's active edge in the
// firmware's clock, applied by run_due(), delivered as edges to the line's
// consumer, recorded in the timeline.
#include "gpio_test_support.hpp"
#include "lightstage/sim/gpio/virtual_chip.hpp"

#include <gtest/gtest.h>

namespace lightstage::sim::gpio {
namespace {

using testing::entries_for;
using testing::shipped_rig;

class StrobeTest : public ::testing::Test {
 protected:
  StrobeTest() {
    VirtualChipOptions options = chip_options_for(rig);
    options.strobe_delay_ns = 1'000;
    options.strobe_exposure_ns = 10'000;
    chip = std::make_unique<VirtualChip>(layout_from_rig(rig), options);
    firmware = chip->connect();
    chip->request_lines(firmware, trigger, true, "fw", {}, {}, 1);
    chip->request_lines(firmware, strobe, false, "fw", {}, {}, 1);
  }
  void pulse_trigger(std::int64_t t_ns) {
    const std::vector<int> on = {1};
    const std::vector<int> off = {0};
    chip->set_values(firmware, trigger, on, t_ns);
    chip->set_values(firmware, trigger, off, t_ns + 100);
  }

  Rig rig = shipped_rig("sim-dome");
  std::unique_ptr<VirtualChip> chip;
  ClientId firmware = 0;
  std::vector<unsigned> trigger = {100};
  std::vector<unsigned> strobe = {101};
};

TEST_F(StrobeTest, DefaultsComeFromTheRig) {
  const auto options = chip_options_for(rig);
  EXPECT_TRUE(options.strobe);
  EXPECT_EQ(options.strobe_exposure_ns, 10'000'000);  // camera.exposure_us: 10000
  EXPECT_FALSE(chip_options_for(shipped_rig("matrix-64")).strobe) << "matrix-64 has no strobe line";
}

TEST_F(StrobeTest, ATriggerSchedulesStrobeEdgesForTheConsumerOfTheStrobeLine) {
  EXPECT_EQ(chip->next_due_ns(), std::nullopt);
  pulse_trigger(50'000);
  ASSERT_EQ(chip->next_due_ns(), 51'000);
  EXPECT_TRUE(chip->run_due(50'999).empty()) << "nothing is due before its time";

  auto edges = chip->run_due(51'000);
  ASSERT_EQ(edges.size(), 1u);
  EXPECT_EQ(edges[0].client, firmware);
  EXPECT_EQ(edges[0].edge.offset, 101u);
  EXPECT_TRUE(edges[0].edge.rising);
  EXPECT_EQ(edges[0].edge.t_ns, 51'000);
  EXPECT_EQ(chip->next_due_ns(), 61'000);

  edges = chip->run_due(1'000'000);  // late: still stamped with the scheduled time
  ASSERT_EQ(edges.size(), 1u);
  EXPECT_FALSE(edges[0].edge.rising);
  EXPECT_EQ(edges[0].edge.t_ns, 61'000);
  EXPECT_EQ(chip->next_due_ns(), std::nullopt);

  const auto strobe_entries = entries_for(chip->timeline(), "STROBE");
  ASSERT_EQ(strobe_entries.size(), 2u);
  EXPECT_EQ(strobe_entries[0].t_ns, 51'000);
  EXPECT_EQ(strobe_entries[0].value, 1);
  EXPECT_EQ(strobe_entries[1].t_ns, 61'000);
  EXPECT_EQ(strobe_entries[1].value, 0);
}

TEST_F(StrobeTest, ActiveLowRequestsSeeRisingAsActive) {
  const ClientId other = chip->connect();
  chip->release_lines(firmware, strobe);
  const bool low[] = {true};
  chip->request_lines(other, strobe, false, "other", low, {}, 1);
  pulse_trigger(0);
  // The strobe is active-high in the rig; an active-low reader sees the
  // exposure start as a falling edge.
  const auto edges = chip->run_due(1'000);
  ASSERT_EQ(edges.size(), 1u);
  EXPECT_EQ(edges[0].client, other);
  EXPECT_FALSE(edges[0].edge.rising);
}

TEST_F(StrobeTest, ATriggerDuringAnExposureIsIgnoredLikeABusyCamera) {
  pulse_trigger(0);
  pulse_trigger(5'000);  // exposure runs 1'000..11'000
  chip->run_due(100'000);
  EXPECT_EQ(entries_for(chip->timeline(), "STROBE").size(), 2u);
  EXPECT_EQ(chip->stats().triggers, 2);
  EXPECT_EQ(chip->stats().strobes, 1);
  EXPECT_EQ(chip->stats().triggers_ignored, 1);
  pulse_trigger(20'000);
  chip->run_due(100'000);
  EXPECT_EQ(entries_for(chip->timeline(), "STROBE").size(), 4u);
}

TEST_F(StrobeTest, NoStrobeWhenTurnedOff) {
  VirtualChipOptions options = chip_options_for(rig);
  options.strobe = false;
  VirtualChip quiet(layout_from_rig(rig), options);
  const ClientId client = quiet.connect();
  quiet.request_lines(client, trigger, true, "fw", {}, {}, 1);
  const std::vector<int> on = {1};
  quiet.set_values(client, trigger, on, 10);
  EXPECT_EQ(quiet.next_due_ns(), std::nullopt);
  EXPECT_EQ(quiet.stats().triggers, 1);
}

TEST_F(StrobeTest, OptionsAreChecked) {
  VirtualChipOptions options;
  options.strobe_exposure_ns = 0;
  EXPECT_THROW(options.check(), InputError);
  options.strobe_exposure_ns = 1;
  options.strobe_delay_ns = -1;
  EXPECT_THROW(options.check(), InputError);
}

}  // namespace
}  // namespace lightstage::sim::gpio
