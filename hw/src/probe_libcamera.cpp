// Cameras that libcamera (0.0.3 in Debian 12) can see.
#include "lightstage/hw/probe.hpp"

#include <libcamera/camera.h>
#include <libcamera/camera_manager.h>

#include <cstring>

namespace lightstage::hw {

ProbeReport probe_libcamera() {
  ProbeReport report{"libcamera", true, {}, {}};
  libcamera::CameraManager manager;
  if (const int ret = manager.start(); ret != 0) {
    report.problem = std::string("camera manager failed to start: ") + std::strerror(-ret);
    return report;
  }
  for (const auto& camera : manager.cameras()) report.devices.push_back({"libcamera:" + camera->id(), camera->id()});
  manager.stop();
  if (report.devices.empty()) report.problem = "no camera found by libcamera";
  return report;
}

}  // namespace lightstage::hw
