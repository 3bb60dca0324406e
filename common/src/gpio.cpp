#include "lightstage/common/gpio.hpp"

namespace lightstage::gpio {

std::optional<unsigned> Chip::find_line(std::string_view name) const {
  const ChipInfo chip = info();
  for (std::size_t i = 0; i < chip.line_names.size(); ++i) {
    if (chip.line_names[i] == name) return static_cast<unsigned>(i);
  }
  return std::nullopt;
}

}  // namespace lightstage::gpio
