// Cameras that libgphoto2 (2.5.30 in Debian 12) detects over USB, with the
// gphoto2: URI that opens each as a shot source.
#include "lightstage/hw/gphoto2_source.hpp"
#include "lightstage/hw/probe.hpp"

namespace lightstage::hw {

ProbeReport probe_gphoto2() {
  ProbeReport report{"gphoto2", true, {}, {}};
  for (const auto& camera : list_gphoto2_cameras())
    report.devices.push_back({camera.uri, camera.model + " (" + camera.driver + ")"});
  if (report.devices.empty()) {
    report.problem =
        "no camera found by libgphoto2 (on, connected, not held by the desktop's auto-mounter? see "
        "hw/docs/cameras.md)";
  }
  return report;
}

}  // namespace lightstage::hw
