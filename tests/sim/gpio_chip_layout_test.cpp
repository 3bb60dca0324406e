// The virtual chip's lines as built from a rig: names, offsets, roles, chains.
#include "gpio_test_support.hpp"
#include "lightstage/sim/gpio/chip_layout.hpp"
#include "lightstage/testing/errors.hpp"

#include <gtest/gtest.h>

namespace lightstage::sim::gpio {
namespace {

using testing::shipped_rig;

TEST(ChipLayout, SimDomeKeepsTheRigOffsetsAndNamesLedLinesByLedId) {
  const ChipLayout layout = layout_from_rig(shipped_rig("sim-dome"));
  ASSERT_EQ(layout.lines.size(), 102u);  // LEDs 0..95, trigger 100, strobe 101
  EXPECT_EQ(layout.lines[0].name, "LED0");
  EXPECT_EQ(layout.lines[17].name, "LED17");
  EXPECT_EQ(layout.lines[17].role, LineRole::kLed);
  EXPECT_EQ(layout.lines[17].led_id, 17);
  EXPECT_EQ(layout.lines[100].name, "TRIGGER");
  EXPECT_EQ(layout.lines[101].name, "STROBE");
  EXPECT_EQ(layout.trigger, 100u);
  EXPECT_EQ(layout.strobe, 101u);
  for (unsigned unused = 96; unused < 100; ++unused) {
    EXPECT_EQ(layout.lines[unused].name, "");
    EXPECT_EQ(layout.lines[unused].role, LineRole::kUnused);
    EXPECT_EQ(layout.display_name(unused), "line" + std::to_string(unused));
  }
  EXPECT_TRUE(layout.chains.empty());
}

TEST(ChipLayout, Matrix64GivesNamedLinesFreeOffsetsInRigOrder) {
  const ChipLayout layout = layout_from_rig(shipped_rig("matrix-64"));
  ASSERT_EQ(layout.lines.size(), 5u);
  EXPECT_EQ(layout.lines[0].name, "CAM_TRIG");
  EXPECT_EQ(layout.lines[1].name, "SR_DATA");
  EXPECT_EQ(layout.lines[2].name, "SR_CLK");
  EXPECT_EQ(layout.lines[3].name, "SR_LATCH");
  EXPECT_EQ(layout.lines[4].name, "SR_OE");
  EXPECT_TRUE(layout.lines[4].active_low);
  EXPECT_FALSE(layout.strobe.has_value());
  ASSERT_EQ(layout.chains.size(), 1u);
  const ChainSpec& chain = layout.chains[0];
  EXPECT_EQ(chain.name, "leds");
  EXPECT_EQ(chain.data, 1u);
  EXPECT_EQ(chain.clock, 2u);
  EXPECT_EQ(chain.latch, 3u);
  EXPECT_EQ(chain.output_enable, 4u);
  ASSERT_EQ(chain.led_by_bit.size(), 64u);
  EXPECT_EQ(chain.led_by_bit[17], 17);
}

TEST(ChipLayout, MixedRigFillsGapsAndKeepsRigNames) {
  const Rig rig = parse_rig(R"(name: mixed
dome_radius_mm: 300
camera: {width: 8, height: 8}
trigger: {line: CAMERA_TRIGGER, active_low: true}
strobe: {line: 3}
led_defaults: {limits: {max_on_us: 1000, max_duty: 0.5}}
leds:
  - {id: 7, line: 0, position_mm: [100, 0, 100]}
  - {id: 8, line: LED_EIGHT, position_mm: [0, 100, 100]}
  - {id: 9, line: 1, position_mm: [-100, 0, 100]}
)",
                            "mixed.yaml");
  const ChipLayout layout = layout_from_rig(rig);
  ASSERT_EQ(layout.lines.size(), 5u);
  EXPECT_EQ(layout.lines[0].name, "LED7");
  EXPECT_EQ(layout.lines[1].name, "LED9");
  EXPECT_EQ(layout.lines[2].name, "CAMERA_TRIGGER");  // first free offset, trigger before LEDs
  EXPECT_TRUE(layout.lines[2].active_low);
  EXPECT_EQ(layout.lines[3].name, "STROBE");
  // No free offset left below 4: the LED line the rig names goes after the highest.
  EXPECT_EQ(layout.lines[4].name, "LED_EIGHT");
  EXPECT_EQ(layout.lines[4].led_id, 8);
  EXPECT_EQ(layout.resolve("LED_EIGHT"), 4u);
}

TEST(ChipLayout, ResolveTakesNamesAndOffsets) {
  const ChipLayout layout = layout_from_rig(shipped_rig("sim-dome"));
  EXPECT_EQ(layout.resolve("LED5"), 5u);
  EXPECT_EQ(layout.resolve("TRIGGER"), 100u);
  EXPECT_EQ(layout.resolve("97"), 97u);
  EXPECT_EQ(layout.resolve("102"), std::nullopt);
  EXPECT_EQ(layout.resolve("NOPE"), std::nullopt);
  EXPECT_EQ(layout.resolve(""), std::nullopt);
}

TEST(ChipLayout, ANameCollisionNamesTheLineAndTheRig) {
  const Rig rig = parse_rig(R"(name: clash
dome_radius_mm: 300
camera: {width: 8, height: 8}
trigger: {line: LED1}
led_defaults: {limits: {max_on_us: 1000, max_duty: 0.5}}
leds:
  - {id: 1, line: 0, position_mm: [100, 0, 100]}
)",
                            "clash.yaml");
  const std::string error = lightstage::testing::error_of([&] { layout_from_rig(rig); });
  EXPECT_NE(error.find("clash.yaml"), std::string::npos) << error;
  EXPECT_NE(error.find("\"LED1\""), std::string::npos) << error;
}

}  // namespace
}  // namespace lightstage::sim::gpio
