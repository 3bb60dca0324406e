#pragma once
// The `gpiod:CHIP` GPIO backend: a real GPIO character device through
// libgpiod. Every libgpiod-v1-specific call lives in hw/src/gpio/gpiod_chip.cpp,
// so moving to libgpiod 2 replaces that one file.
//
// CHIP may be a device path ("/dev/gpiochip0"), a chip name ("gpiochip0"), a
// chip label ("pinctrl-bcm2711"), a chip number ("0"), or the name of a line
// the chip carries ("SR_DATA") -- chip numbers differ between boards, labels
// and line names do not.

#include "lightstage/common/gpio.hpp"

#include <cstddef>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace lightstage::hw {

// Opens the chip; throws gpio::GpioError naming `chip_spec` (and the chips
// that do exist) when there is none, or when this build lacks libgpiod.
std::unique_ptr<gpio::Chip> open_gpiod_chip(const std::string& chip_spec);

// libgpiod v1 requests at most this many lines in one bulk request.
inline constexpr std::size_t kGpiodMaxBulkLines = 64;

// How `count` lines are split into bulk requests: [first, first + size) ranges
// of at most `max_per_bulk` lines, in order.
std::vector<std::pair<std::size_t, std::size_t>> bulk_ranges(std::size_t count,
                                                             std::size_t max_per_bulk = kGpiodMaxBulkLines);

}  // namespace lightstage::hw
