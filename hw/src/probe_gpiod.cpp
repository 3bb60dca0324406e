// GPIO chips through libgpiod 1.6 (its C++ binding). v1-specific calls stay in
// files like this one so that a move to libgpiod 2 touches little.
#include "lightstage/hw/probe.hpp"

#include <fmt/format.h>
#include <gpiod.hpp>

#include <system_error>

namespace lightstage::hw {

ProbeReport probe_gpiod() {
  ProbeReport report{"gpiod", true, {}, {}};
  try {
    for (const auto& chip : ::gpiod::make_chip_iter()) {
      report.devices.push_back(
          {"gpiod:" + chip.name(), fmt::format("label \"{}\", {} lines", chip.label(), chip.num_lines())});
    }
  } catch (const std::system_error& e) {
    report.problem = e.what();
  }
  if (report.devices.empty() && report.problem.empty()) report.problem = "no /dev/gpiochip* on this machine";
  return report;
}

}  // namespace lightstage::hw
