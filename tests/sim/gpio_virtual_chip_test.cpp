// The virtual chip's model: consumers, values, the timeline with the
// firmware's timestamps, polarity, and the JSON-lines timeline file.
#include "gpio_test_support.hpp"
#include "lightstage/sim/gpio/virtual_chip.hpp"
#include "lightstage/testing/paths.hpp"

#include <gtest/gtest.h>

#include <fstream>

namespace lightstage::sim::gpio {
namespace {

using lightstage::gpio::GpioError;
using testing::entries_for;
using testing::shipped_rig;

std::string gpio_error_of(const std::function<void()>& action) {
  try {
    action();
  } catch (const GpioError& e) {
    return e.what();
  }
  return "(no GpioError)";
}

class VirtualChipTest : public ::testing::Test {
 protected:
  Rig rig = shipped_rig("sim-dome");
  VirtualChip chip{layout_from_rig(rig), chip_options_for(rig)};
};

TEST_F(VirtualChipTest, InfoListsTheRigLinesAndTheirConsumers) {
  const ClientId firmware = chip.connect();
  const std::vector<unsigned> leds = {3, 4};
  chip.request_lines(firmware, leds, true, "lightstage-domed", {}, {}, 1);
  const auto info = chip.info();
  EXPECT_EQ(info.label, "lightstage-sim");
  ASSERT_EQ(info.line_names.size(), 102u);
  EXPECT_EQ(info.line_names[3], "LED3");
  EXPECT_EQ(info.consumers[3], "lightstage-domed");
  EXPECT_EQ(info.consumers[4], "lightstage-domed");
  EXPECT_EQ(info.consumers[5], "");
}

TEST_F(VirtualChipTest, ALineRequestedTwiceNamesTheLineAndItsConsumer) {
  const ClientId first = chip.connect();
  const ClientId second = chip.connect();
  const std::vector<unsigned> led17 = {17};
  chip.request_lines(first, led17, true, "lightstage-domed", {}, {}, 1);
  const std::string error =
      gpio_error_of([&] { chip.request_lines(second, led17, true, "intruder", {}, {}, 2); });
  EXPECT_NE(error.find("LED17"), std::string::npos) << error;
  EXPECT_NE(error.find("lightstage-domed"), std::string::npos) << error;
  // The same client asking again is refused too: a line has one consumer.
  EXPECT_NE(gpio_error_of([&] { chip.request_lines(first, led17, true, "again", {}, {}, 2); }),
            "(no GpioError)");
}

TEST_F(VirtualChipTest, ReleaseAndDisconnectFreeLines) {
  const ClientId first = chip.connect();
  const std::vector<unsigned> lines = {1, 2};
  chip.request_lines(first, lines, true, "a", {}, {}, 1);
  const std::vector<unsigned> one = {1};
  chip.release_lines(first, one);
  EXPECT_EQ(chip.info().consumers[1], "");
  EXPECT_EQ(chip.info().consumers[2], "a");
  chip.disconnect(first);
  EXPECT_EQ(chip.info().consumers[2], "");
  const ClientId second = chip.connect();
  EXPECT_NO_THROW(chip.request_lines(second, lines, true, "b", {}, {}, 2));
}

// A firmware that dies without darkening the dome: its lines are freed and,
// as the rig's pull resistors would, fall to inactive — LEDs dark.
TEST_F(VirtualChipTest, ADisconnectedFirmwaresLitLedsFallDark) {
  const ClientId firmware = chip.connect();
  const std::vector<unsigned> lines = {7, 8};
  chip.request_lines(firmware, lines, true, "lightstage-domed", {}, {}, 1);
  const std::vector<int> on = {1, 1};
  chip.set_values(firmware, lines, on, 10);
  EXPECT_TRUE(chip.led_lit(7));
  chip.disconnect(firmware);
  EXPECT_FALSE(chip.led_lit(7));
  EXPECT_FALSE(chip.led_lit(8));
  const auto entries = entries_for(chip.timeline(), "LED7");
  ASSERT_GE(entries.size(), 2u);
  EXPECT_EQ(entries[entries.size() - 2].value, 1);
  EXPECT_EQ(entries.back().value, 0);
  EXPECT_GT(entries.back().t_ns, 10);
}

TEST_F(VirtualChipTest, BadRequestsNameTheLine) {
  const ClientId client = chip.connect();
  const std::vector<unsigned> missing = {130};
  EXPECT_NE(gpio_error_of([&] { chip.request_lines(client, missing, true, "x", {}, {}, 1); }).find("130"),
            std::string::npos);
  const std::vector<unsigned> twice = {5, 5};
  EXPECT_NE(gpio_error_of([&] { chip.request_lines(client, twice, true, "x", {}, {}, 1); }).find("LED5"),
            std::string::npos);
  const std::vector<unsigned> led9 = {9};
  const std::vector<int> on = {1};
  const std::string error = gpio_error_of([&] { chip.set_values(client, led9, on, 5); });
  EXPECT_NE(error.find("LED9"), std::string::npos) << error;
  EXPECT_NE(error.find("not requested as an output"), std::string::npos) << error;
}

TEST_F(VirtualChipTest, TimelineRecordsEveryChangeWithTheFirmwareTimestamps) {
  const ClientId firmware = chip.connect();
  const std::vector<unsigned> lines = {17, 18};
  chip.request_lines(firmware, lines, true, "fw", {}, {}, 1000);  // initial 0: no change
  const std::vector<int> on17 = {1, 0};
  const std::vector<int> on_both = {1, 1};
  const std::vector<int> off = {0, 0};
  chip.set_values(firmware, lines, on17, 2000);
  chip.set_values(firmware, lines, on17, 2500);  // no change: nothing recorded
  chip.set_values(firmware, lines, on_both, 3000);
  chip.set_values(firmware, lines, off, 4000);
  const auto timeline = chip.timeline();
  ASSERT_EQ(timeline.size(), 4u);
  EXPECT_EQ(timeline[0].t_ns, 2000);
  EXPECT_EQ(timeline[0].line, "LED17");
  EXPECT_EQ(timeline[0].value, 1);
  EXPECT_EQ(timeline[0].led, 17);
  EXPECT_EQ(timeline[1].t_ns, 3000);
  EXPECT_EQ(timeline[1].line, "LED18");
  EXPECT_EQ(timeline[2].t_ns, 4000);
  EXPECT_EQ(timeline[2].value, 0);
  EXPECT_EQ(timeline[3].t_ns, 4000);
  EXPECT_FALSE(chip.led_lit(17));
  EXPECT_EQ(chip.active_value(17), 0);
}

TEST_F(VirtualChipTest, InitialValuesAreRecordedAtTheRequestTime) {
  const ClientId firmware = chip.connect();
  const std::vector<unsigned> lines = {7, 8};
  const std::vector<int> initial = {0, 1};
  chip.request_lines(firmware, lines, true, "fw", {}, initial, 500);
  const auto timeline = chip.timeline();
  ASSERT_EQ(timeline.size(), 1u);
  EXPECT_EQ(timeline[0].line, "LED8");
  EXPECT_EQ(timeline[0].t_ns, 500);
  EXPECT_TRUE(chip.led_lit(8));
}

// A rig whose trigger is wired active-low, its chip and a firmware connected to it.
class VirtualChipPolarity : public ::testing::Test {
 protected:
  const Rig rig = parse_rig(R"(name: low
dome_radius_mm: 300
camera: {width: 8, height: 8}
trigger: {line: {line: 2, active_low: true}}
led_defaults: {limits: {max_on_us: 1000, max_duty: 0.5}}
leds:
  - {id: 1, line: 0, position_mm: [100, 0, 100]}
)",
                            "low.yaml");
  VirtualChip chip{layout_from_rig(rig), chip_options_for(rig)};
  const ClientId firmware = chip.connect();
};

TEST_F(VirtualChipPolarity, TimelineValuesAreActiveAsTheRigWiresTheLine) {
  // A trigger wired active-low: the firmware requests it active-low and sets
  // logical 1; the level goes low and the timeline says the trigger is active.
  const std::vector<unsigned> trigger = {2};
  const bool low[] = {true};
  chip.request_lines(firmware, trigger, true, "fw", low, {}, 10);
  EXPECT_TRUE(chip.timeline().empty()) << "inactive at start and after the request";
  const std::vector<int> on = {1};
  chip.set_values(firmware, trigger, on, 20);
  ASSERT_EQ(chip.timeline().size(), 1u);
  EXPECT_EQ(chip.timeline()[0].line, "TRIGGER");
  EXPECT_EQ(chip.timeline()[0].value, 1);
  EXPECT_EQ(chip.stats().triggers, 1);
}

TEST_F(VirtualChipPolarity, AFirmwareIgnoringTheRigPolarityShowsInTheTimeline) {
  const std::vector<unsigned> trigger = {2};
  const std::vector<int> initial = {0};
  // Requested active-high with logical 0: the line goes low, i.e. the trigger fires.
  chip.request_lines(firmware, trigger, true, "fw", {}, initial, 10);
  ASSERT_EQ(chip.timeline().size(), 1u);
  EXPECT_EQ(chip.timeline()[0].value, 1);
}

TEST(TimelineJson, EntriesReadLikeTheIssueExample) {
  EXPECT_EQ(to_json_line({123, "LED17", 1, 17, ""}), R"({"t_ns":123,"line":"LED17","value":1,"led":17})");
  EXPECT_EQ(to_json_line({5, "TRIGGER", 0, -1, ""}), R"({"t_ns":5,"line":"TRIGGER","value":0})");
  EXPECT_EQ(to_json_line({7, "LED40", 1, 40, "leds"}),
            R"({"t_ns":7,"line":"LED40","value":1,"led":40,"via":"leds"})");
  EXPECT_EQ(to_json_line({7, "odd\"name", 1, -1, ""}), R"({"t_ns":7,"line":"odd\"name","value":1})");
}

TEST(TimelineJson, TheFileIsAppendedAndReadableWhileTheSinkLives) {
  const auto path = lightstage::testing::scratch_dir() / "timeline.jsonl";
  { std::ofstream(path) << "{\"earlier\":true}\n"; }
  const Rig rig = shipped_rig("sim-dome");
  VirtualChip chip(layout_from_rig(rig), chip_options_for(rig));
  chip.add_timeline_sink(std::make_shared<JsonLinesTimelineFile>(path));
  const ClientId firmware = chip.connect();
  const std::vector<unsigned> led = {17};
  chip.request_lines(firmware, led, true, "fw", {}, {}, 1);
  const std::vector<int> on = {1};
  chip.set_values(firmware, led, on, 42);
  // No close, no destructor: the batch is already flushed.
  std::ifstream in(path);
  std::string first;
  std::string second;
  std::getline(in, first);
  std::getline(in, second);
  EXPECT_EQ(first, "{\"earlier\":true}");
  EXPECT_EQ(second, R"({"t_ns":42,"line":"LED17","value":1,"led":17})");
}

TEST(TimelineJson, AnUnwritablePathIsAnInputErrorNamingIt) {
  try {
    JsonLinesTimelineFile sink("/nonexistent-dir/timeline.jsonl");
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-dir/timeline.jsonl"), std::string::npos);
  }
}

}  // namespace
}  // namespace lightstage::sim::gpio
