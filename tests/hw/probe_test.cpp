// The real backends are built here but this machine has no GPIO chip, camera
// or USB bus: probing must report that cleanly, never crash or hang.
#include "lightstage/hw/probe.hpp"
#include "gphoto2_leaks.hpp"
#include "lightstage/hw/backends.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <set>

namespace lightstage::hw {
namespace {

TEST(Probe, EveryBackendReportsDevicesOrAReason) {
  std::set<std::string> schemes;
  for (const ProbeReport& report : probe_devices()) {
    schemes.insert(report.scheme);
    EXPECT_EQ(report.built, backend_built(report.scheme)) << report.scheme;
    EXPECT_TRUE(!report.devices.empty() || !report.problem.empty()) << report.scheme;
    for (const auto& device : report.devices) {
      EXPECT_EQ(device.uri.rfind(report.scheme + ":", 0), 0u) << device.uri;
    }
  }
  EXPECT_EQ(schemes, (std::set<std::string>{"gpiod", "v4l2", "libcamera", "aravis", "gphoto2", "usb"}));
}

TEST(Probe, GpioChipsMatchTheDevFolder) {
  if (!backend_built("gpiod")) GTEST_SKIP() << "built without libgpiod";
  std::size_t chips_in_dev = 0;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator("/dev", ec)) {
    if (entry.path().filename().string().rfind("gpiochip", 0) == 0) ++chips_in_dev;
  }
  EXPECT_EQ(probe_gpiod().devices.size(), chips_in_dev);
}

}  // namespace
}  // namespace lightstage::hw
