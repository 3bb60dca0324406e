// GenICam cameras (GigE Vision, USB3 Vision) that aravis 0.8 sees, listed
// through the aravis: camera backend. Finding GigE cameras broadcasts on
// every network interface and waits for answers (about a second).
#include "lightstage/hw/cameras.hpp"
#include "lightstage/hw/probe.hpp"

namespace lightstage::hw {

ProbeReport probe_aravis() {
  ProbeReport report{"aravis", true, {}, {}};
  try {
    for (const auto& camera : aravis_camera_scheme().list())
      report.devices.push_back({camera.uri, camera.model + " (" + camera.driver + ")"});
  } catch (const std::exception& e) {
    report.problem = e.what();
    return report;
  }
  if (report.devices.empty()) report.problem = "no GenICam camera found by aravis";
  return report;
}

}  // namespace lightstage::hw
