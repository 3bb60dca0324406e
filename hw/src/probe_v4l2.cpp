// Video4Linux2 capture devices: /dev/video* that the v4l2: camera backend
// can open (single-planar capture with streaming, a format it can unpack).
#include "lightstage/hw/cameras.hpp"
#include "lightstage/hw/probe.hpp"

#include <fmt/format.h>

namespace lightstage::hw {

ProbeReport probe_v4l2() {
  ProbeReport report{"v4l2", true, {}, {}};
  // Through the v4l2: camera backend: what it lists, it can open and stream.
  for (const auto& camera : v4l2_camera_scheme().list()) {
    report.devices.push_back({camera.uri, fmt::format("{} ({})", camera.model, camera.driver)});
  }
  if (report.devices.empty())
    report.problem = "no V4L2 capture device in /dev that Lightstage can stream from";
  return report;
}

}  // namespace lightstage::hw
