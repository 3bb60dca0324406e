// Video4Linux2 capture devices: /dev/video* that answer VIDIOC_QUERYCAP with
// the video-capture capability.
#include "lightstage/hw/probe.hpp"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <fmt/format.h>
#include <filesystem>
#include <string>

namespace lightstage::hw {

ProbeReport probe_v4l2() {
  ProbeReport report{"v4l2", true, {}, {}};
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator("/dev", ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("video", 0) != 0) continue;
    const int fd = ::open(entry.path().c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) continue;
    v4l2_capability caps{};
    if (::ioctl(fd, VIDIOC_QUERYCAP, &caps) == 0) {
      const auto device_caps =
          (caps.capabilities & V4L2_CAP_DEVICE_CAPS) ? caps.device_caps : caps.capabilities;
      if (device_caps & (V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_VIDEO_CAPTURE_MPLANE)) {
        report.devices.push_back(
            {"v4l2:" + entry.path().string(), fmt::format("{} ({})", reinterpret_cast<const char*>(caps.card),
                                                          reinterpret_cast<const char*>(caps.driver))});
      }
    }
    ::close(fd);
  }
  if (report.devices.empty()) report.problem = "no V4L2 capture device in /dev";
  return report;
}

}  // namespace lightstage::hw
