#pragma once
// Which real hardware backends this build carries. Each is optional at build
// time (see cmake/LightstageDependencies.cmake) so a machine without libgpiod,
// libcamera, aravis, libgphoto2, libusb or V4L2 headers still builds; asking for a missing one by
// URI gets an error that says the build lacks it.

#include <string>
#include <vector>

namespace lightstage::hw {

struct BackendInfo {
  std::string scheme;  // URI scheme: "gpiod", "libcamera", "aravis", "gphoto2", "usb", "v4l2"
  std::string what;    // what it drives
  bool built = false;
};

std::vector<BackendInfo> hardware_backends();
bool backend_built(const std::string& scheme);

}  // namespace lightstage::hw
