#pragma once
// Opens the GPIO backend a URI names: "gpiod:CHIP" (a real chip through
// libgpiod; hw/gpiod_chip.hpp) or "sim:/path/to/sim.sock" (lightstage-sim's
// virtual chip). Throws InputError for a malformed URI, gpio::GpioError
// (naming the URI) when the chip cannot be opened.

#include "lightstage/common/gpio.hpp"

#include <memory>
#include <string>

namespace lightstage::firmware {

std::unique_ptr<gpio::Chip> open_gpio_chip(const std::string& uri);

}  // namespace lightstage::firmware
