// Cameras that libcamera (0.0.3 in Debian 12) can see, listed through the
// libcamera: camera backend (which shares the process's one CameraManager).
#include "lightstage/hw/cameras.hpp"
#include "lightstage/hw/probe.hpp"

namespace lightstage::hw {

ProbeReport probe_libcamera() {
  ProbeReport report{"libcamera", true, {}, {}};
  try {
    for (const auto& camera : libcamera_camera_scheme().list())
      report.devices.push_back({camera.uri, camera.model});
  } catch (const std::exception& e) {
    report.problem = e.what();
    return report;
  }
  if (report.devices.empty()) report.problem = "no camera found by libcamera";
  return report;
}

}  // namespace lightstage::hw
