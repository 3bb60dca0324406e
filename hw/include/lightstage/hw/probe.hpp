#pragma once
// What hardware this machine can see, per backend: GPIO chips, V4L2,
// libcamera and GenICam (aravis) cameras, DSLR / mirrorless cameras
// (gphoto2), USB devices. `lightstage devices` prints it, so an
// operator can find the URI to pass before anything is opened for real.

#include <string>
#include <vector>

namespace lightstage::hw {

struct DeviceInfo {
  std::string uri;          // what to pass as --gpio / --camera / --controller
  std::string description;  // label, driver, card name, ...
};

struct ProbeReport {
  std::string scheme;  // "gpiod", "v4l2", "libcamera", "aravis", "gphoto2", "usb"
  bool built = false;  // false: this build has no such backend
  std::vector<DeviceInfo> devices;
  std::string problem;  // why enumeration failed, when it did (e.g. no USB support)
};

std::vector<ProbeReport> probe_devices();

// One per backend; each lives in its own file, compiled only with its library.
ProbeReport probe_gpiod();
ProbeReport probe_v4l2();
ProbeReport probe_libcamera();
ProbeReport probe_aravis();
ProbeReport probe_gphoto2();
ProbeReport probe_usb();

}  // namespace lightstage::hw
