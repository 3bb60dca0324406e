#include "lightstage/firmware/gpio_uri.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/hw/gpiod_chip.hpp"

#ifdef LIGHTSTAGE_HAVE_SIM_GPIO
#include "lightstage/sim/gpio/sim_chip.hpp"
#endif

#include <fmt/format.h>

namespace lightstage::firmware {

std::unique_ptr<gpio::Chip> open_gpio_chip(const std::string& uri) {
  const auto colon = uri.find(':');
  const std::string scheme = colon == std::string::npos ? uri : uri.substr(0, colon);
  const std::string rest = colon == std::string::npos ? std::string() : uri.substr(colon + 1);
  if (scheme == "gpiod") return hw::open_gpiod_chip(rest);
  if (scheme == "sim") {
    if (rest.empty()) fail("GPIO URI '{}': give the simulator's socket, sim:/path/to/sim.sock", uri);
#ifdef LIGHTSTAGE_HAVE_SIM_GPIO
    return sim::gpio::connect_sim_chip(rest);
#else
    throw gpio::GpioError(fmt::format("{}: this build has no sim: GPIO client (lightstage_sim_gpio)", uri));
#endif
  }
  fail("GPIO URI '{}': unknown scheme '{}' (expected gpiod:CHIP or sim:/path/to/sim.sock)", uri, scheme);
}

}  // namespace lightstage::firmware
