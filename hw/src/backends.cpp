#include "lightstage/hw/backends.hpp"

namespace lightstage::hw {

std::vector<BackendInfo> hardware_backends() {
  return {
#ifdef LIGHTSTAGE_HAVE_GPIOD
      {"gpiod", "GPIO lines through libgpiod", true},
#else
      {"gpiod", "GPIO lines through libgpiod", false},
#endif
#ifdef LIGHTSTAGE_HAVE_LIBCAMERA
      {"libcamera", "cameras through libcamera", true},
#else
      {"libcamera", "cameras through libcamera", false},
#endif
#ifdef LIGHTSTAGE_HAVE_ARAVIS
      {"aravis", "GenICam cameras (GigE Vision, USB3 Vision) through aravis", true},
#else
      {"aravis", "GenICam cameras (GigE Vision, USB3 Vision) through aravis", false},
#endif
#ifdef LIGHTSTAGE_HAVE_GPHOTO2
      {"gphoto2", "DSLR and mirrorless cameras over USB through libgphoto2", true},
#else
      {"gphoto2", "DSLR and mirrorless cameras over USB through libgphoto2", false},
#endif
#ifdef LIGHTSTAGE_HAVE_LIBUSB
      {"usb", "the dome controller over USB (libusb)", true},
#else
      {"usb", "the dome controller over USB (libusb)", false},
#endif
#ifdef LIGHTSTAGE_HAVE_V4L2
      {"v4l2", "cameras through Video4Linux2", true},
#else
      {"v4l2", "cameras through Video4Linux2", false},
#endif
  };
}

bool backend_built(const std::string& scheme) {
  for (const auto& backend : hardware_backends()) {
    if (backend.scheme == scheme) return backend.built;
  }
  return false;
}

}  // namespace lightstage::hw
