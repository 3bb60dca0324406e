// `lightstage devices`: what hardware this machine can see, backend by backend.
#include "commands.hpp"

#include "lightstage/hw/probe.hpp"

#include <fmt/format.h>

namespace lightstage::cli {

void add_devices(CLI::App& app) {
  CLI::App* sub = app.add_subcommand(
      "devices",
      "List the hardware this machine can see: GPIO chips, V4L2, libcamera, GenICam (aravis) and "
      "gphoto2 cameras, USB devices, each with the URI to pass to other commands.\n"
      "Nothing is opened for writing and no line is touched.\n"
      "Example: lightstage devices");
  sub->callback([] {
    for (const auto& report : hw::probe_devices()) {
      fmt::print("{}:\n", report.scheme);
      if (!report.built) {
        fmt::print("  ({})\n", report.problem);
        continue;
      }
      for (const auto& device : report.devices) fmt::print("  {:32} {}\n", device.uri, device.description);
      if (report.devices.empty()) fmt::print("  none ({})\n", report.problem);
    }
  });
}

}  // namespace lightstage::cli
