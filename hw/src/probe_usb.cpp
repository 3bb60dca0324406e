// USB devices through libusb: the dome controller shows up here as usb:VID:PID.
#include "lightstage/hw/probe.hpp"

#include <fmt/format.h>
#include <libusb.h>

namespace lightstage::hw {

ProbeReport probe_usb() {
  ProbeReport report{"usb", true, {}, {}};
  libusb_context* context = nullptr;
  if (const int ret = libusb_init(&context); ret != 0) {
    report.problem = fmt::format("libusb_init failed: {}", libusb_strerror(ret));
    return report;
  }
  libusb_device** list = nullptr;
  const ssize_t count = libusb_get_device_list(context, &list);
  if (count < 0) {
    report.problem = fmt::format("cannot list USB devices: {}", libusb_strerror(static_cast<int>(count)));
  }
  for (ssize_t i = 0; i < count; ++i) {
    libusb_device_descriptor descriptor{};
    if (libusb_get_device_descriptor(list[i], &descriptor) != 0) continue;
    report.devices.push_back({fmt::format("usb:{:04x}:{:04x}", descriptor.idVendor, descriptor.idProduct),
                              fmt::format("bus {} address {}", libusb_get_bus_number(list[i]),
                                          libusb_get_device_address(list[i]))});
  }
  if (count >= 0) libusb_free_device_list(list, 1);
  libusb_exit(context);
  if (report.devices.empty() && report.problem.empty()) report.problem = "no USB devices visible";
  return report;
}

}  // namespace lightstage::hw
