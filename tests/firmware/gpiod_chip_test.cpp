// The gpiod: backend's error paths. This machine has no /dev/gpiochip*, so the
// tests check what a user reads when the chip is missing; on a board with
// chips the same tests still hold (the names used here exist nowhere).
#include "lightstage/hw/gpiod_chip.hpp"

#include "lightstage/firmware/gpio_uri.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace lightstage::hw {
namespace {

using ::testing::HasSubstr;

std::string gpio_error(const std::function<void()>& action) {
  try {
    action();
  } catch (const gpio::GpioError& e) {
    return e.what();
  }
  return "(no GpioError)";
}

std::string input_error(const std::function<void()>& action) {
  try {
    action();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no InputError)";
}

TEST(GpiodChip, NamesAChipPathThatDoesNotExist) {
  const std::string message = gpio_error([] { open_gpiod_chip("/dev/gpiochip-lightstage-missing"); });
  EXPECT_THAT(message, HasSubstr("gpiod:/dev/gpiochip-lightstage-missing"));
#ifdef LIGHTSTAGE_HAVE_GPIOD
  EXPECT_THAT(message, HasSubstr("no GPIO chip"));
  EXPECT_THAT(message, HasSubstr("chips on this machine:"));
#else
  EXPECT_THAT(message, HasSubstr("no libgpiod backend"));
#endif
}

TEST(GpiodChip, NamesALabelOrLineNameThatNoChipCarries) {
  const std::string message = gpio_error([] { open_gpiod_chip("LIGHTSTAGE_NO_SUCH_LINE"); });
  EXPECT_THAT(message, HasSubstr("LIGHTSTAGE_NO_SUCH_LINE"));
#ifdef LIGHTSTAGE_HAVE_GPIOD
  EXPECT_THAT(message, HasSubstr("no chip has a line named \"LIGHTSTAGE_NO_SUCH_LINE\""));
#endif
}

TEST(GpiodChip, AsksForAChipWhenNoneIsNamed) {
  EXPECT_THAT(gpio_error([] { open_gpiod_chip(""); }), HasSubstr("gpiod:"));
}

TEST(GpiodChip, SplitsLargeRequestsIntoBulksOfAtMost64Lines) {
  using Ranges = std::vector<std::pair<std::size_t, std::size_t>>;
  EXPECT_EQ(bulk_ranges(0), Ranges{});
  EXPECT_EQ(bulk_ranges(64), (Ranges{{0, 64}}));
  EXPECT_EQ(bulk_ranges(96), (Ranges{{0, 64}, {64, 32}}));
  EXPECT_EQ(bulk_ranges(129), (Ranges{{0, 64}, {64, 64}, {128, 1}}));
  EXPECT_EQ(bulk_ranges(5, 2), (Ranges{{0, 2}, {2, 2}, {4, 1}}));
}

TEST(GpioUri, RoutesSchemesAndNamesBadUris) {
  EXPECT_THAT(gpio_error([] { firmware::open_gpio_chip("gpiod:/dev/gpiochip-lightstage-missing"); }),
              HasSubstr("gpiochip-lightstage-missing"));
  EXPECT_THAT(input_error([] { firmware::open_gpio_chip("spi:/dev/spidev0.0"); }),
              HasSubstr("unknown scheme 'spi'"));
  EXPECT_THAT(input_error([] { firmware::open_gpio_chip("sim:"); }), HasSubstr("sim:/path/to/sim.sock"));
}

}  // namespace
}  // namespace lightstage::hw
