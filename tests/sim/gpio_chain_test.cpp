// Shift-register chains: the 74HC595 model, and LED events decoded from a
// bit-banged stream on the matrix-64 rig's SR_DATA/SR_CLK/SR_LATCH/SR_OE.
#include "gpio_test_support.hpp"
#include "lightstage/sim/gpio/shift_register.hpp"
#include "lightstage/sim/gpio/virtual_chip.hpp"

#include <gtest/gtest.h>

namespace lightstage::sim::gpio {
namespace {

using testing::led_entries;
using testing::shipped_rig;
using testing::write_chain;

ShiftRegisterPins pins(bool data, bool clock, bool latch, bool oe = true) { return {data, clock, latch, oe}; }

TEST(ShiftRegisterModel, ShiftsOnClockRiseAndShowsOnLatchRise) {
  ShiftRegisterChainModel chain(8, false);
  // Shift in 1, 0, 0: the 1 ends at bit 2 (the first bit shifted travels furthest).
  for (const bool bit : {true, false, false}) {
    EXPECT_FALSE(chain.step(pins(bit, false, false)));
    EXPECT_FALSE(chain.step(pins(bit, true, false)));
  }
  EXPECT_TRUE(chain.shift_register()[2]);
  EXPECT_FALSE(chain.output(2)) << "not latched yet";
  EXPECT_TRUE(chain.step(pins(false, false, true)));
  EXPECT_TRUE(chain.output(2));
  EXPECT_FALSE(chain.output(0));
  // Falling edges do nothing.
  EXPECT_FALSE(chain.step(pins(false, false, false)));
  EXPECT_TRUE(chain.output(2));
}

TEST(ShiftRegisterModel, EdgesInOneStepSampleThePinsBeforeIt) {
  ShiftRegisterChainModel chain(4, false);
  // Data and clock rising together: the old data (0) is shifted, as on the hardware.
  chain.step(pins(true, true, false));
  EXPECT_FALSE(chain.shift_register()[0]);
  chain.step(pins(true, false, false));
  chain.step(pins(true, true, false));
  EXPECT_TRUE(chain.shift_register()[0]);
  // Latch and clock rising together: the storage gets the bits before the shift.
  chain.step(pins(false, false, false));
  chain.step(pins(false, true, true));
  EXPECT_TRUE(chain.storage()[0]);
  EXPECT_FALSE(chain.storage()[1]);
  EXPECT_TRUE(chain.shift_register()[1]);
}

TEST(ShiftRegisterModel, OutputEnableGatesTheOutputs) {
  ShiftRegisterChainModel chain(2, true);
  chain.step(pins(true, false, false, false));
  chain.step(pins(true, true, false, false));
  EXPECT_FALSE(chain.step(pins(true, false, true, false))) << "latched, but outputs disabled";
  EXPECT_FALSE(chain.output(0));
  EXPECT_TRUE(chain.step(pins(true, false, true, true)));
  EXPECT_TRUE(chain.output(0));
  EXPECT_TRUE(chain.step(pins(true, false, true, false)));
  EXPECT_FALSE(chain.output(0));
}

class Matrix64Chain : public ::testing::Test {
 protected:
  Matrix64Chain() {
    firmware = chip.connect();
    // Data, clock, latch, OE; OE requested active-low as the rig wires it.
    const bool active_low[] = {false, false, false, true};
    chip.request_lines(firmware, lines, true, "fw", active_low, {}, 1);
  }
  void set(const std::vector<int>& values, std::int64_t t_ns) {
    chip.set_values(firmware, lines, values, t_ns);
  }
  testing::SetPins setter() {
    return [this](const std::vector<int>& values, std::int64_t t_ns) { set(values, t_ns); };
  }
  static std::vector<bool> only(std::initializer_list<int> bits) {
    std::vector<bool> out(64, false);
    for (const int bit : bits) out[static_cast<std::size_t>(bit)] = true;
    return out;
  }

  Rig rig = shipped_rig("matrix-64");
  VirtualChip chip{layout_from_rig(rig), chip_options_for(rig)};
  ClientId firmware = 0;
  std::vector<unsigned> lines = {1, 2, 3, 4};  // SR_DATA, SR_CLK, SR_LATCH, SR_OE
};

TEST_F(Matrix64Chain, ABitBangedStreamLightsExactlyTheLedsOfItsBits) {
  const std::int64_t latched = write_chain(setter(), only({17, 40}), 1000);
  auto leds = led_entries(chip.timeline());
  ASSERT_EQ(leds.size(), 2u);
  for (const auto& entry : leds) {
    EXPECT_EQ(entry.value, 1);
    EXPECT_EQ(entry.via, "leds");
    EXPECT_EQ(entry.line, "LED" + std::to_string(entry.led));
    // Lit at the latch's rising edge, stamped with the firmware's time.
    EXPECT_EQ(entry.t_ns, latched - 10);
  }
  EXPECT_EQ(leds[0].led, 17);
  EXPECT_EQ(leds[1].led, 40);
  EXPECT_TRUE(chip.led_lit(17));
  EXPECT_TRUE(chip.led_lit(40));
  EXPECT_FALSE(chip.led_lit(16));

  // The next frame turns 17 off, keeps 40, lights 63.
  const std::int64_t second = write_chain(setter(), only({40, 63}), latched + 1000);
  leds = led_entries(chip.timeline());
  ASSERT_EQ(leds.size(), 4u);
  EXPECT_EQ(leds[2].led, 17);
  EXPECT_EQ(leds[2].value, 0);
  EXPECT_EQ(leds[3].led, 63);
  EXPECT_EQ(leds[3].value, 1);
  EXPECT_EQ(leds[3].t_ns, second - 10);
}

TEST_F(Matrix64Chain, NothingIsLitWhileOutputEnableIsInactive) {
  // Shift and latch with OE inactive (logical 0 = level high on the active-low pin).
  const auto bits = only({5});
  std::int64_t t = 100;
  for (std::size_t i = bits.size(); i-- > 0;) {
    const int d = bits[i] ? 1 : 0;
    set({d, 0, 0, 0}, t += 10);
    set({d, 1, 0, 0}, t += 10);
  }
  set({0, 0, 1, 0}, t += 10);
  EXPECT_TRUE(led_entries(chip.timeline()).empty());
  EXPECT_FALSE(chip.led_lit(5));
  set({0, 0, 1, 1}, t += 10);  // enable
  auto leds = led_entries(chip.timeline());
  ASSERT_EQ(leds.size(), 1u);
  EXPECT_EQ(leds[0].led, 5);
  EXPECT_EQ(leds[0].t_ns, t);
  set({0, 0, 1, 0}, t += 10);  // disable darkens it
  leds = led_entries(chip.timeline());
  ASSERT_EQ(leds.size(), 2u);
  EXPECT_EQ(leds[1].value, 0);
  EXPECT_EQ(leds[1].t_ns, t);
}

TEST_F(Matrix64Chain, RawChainLinesAreInTheTimelineToo) {
  write_chain(setter(), only({0}), 0);
  const auto timeline = chip.timeline();
  const auto clocks = testing::entries_for(timeline, "SR_CLK");
  EXPECT_EQ(clocks.size(), 128u);  // 64 rising and 64 falling edges
  EXPECT_EQ(testing::entries_for(timeline, "SR_LATCH").size(), 2u);
  // OE became active with the first set.
  const auto oe = testing::entries_for(timeline, "SR_OE");
  ASSERT_EQ(oe.size(), 1u);
  EXPECT_EQ(oe[0].value, 1);
}

}  // namespace
}  // namespace lightstage::sim::gpio
