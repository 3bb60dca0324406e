#include "lightstage/hw/probe.hpp"

namespace lightstage::hw {

std::vector<ProbeReport> probe_devices() {
  return {probe_gpiod(), probe_v4l2(), probe_libcamera(), probe_aravis(), probe_gphoto2(), probe_usb()};
}

#ifndef LIGHTSTAGE_HAVE_GPIOD
ProbeReport probe_gpiod() { return {"gpiod", false, {}, "built without libgpiod"}; }
#endif
#ifndef LIGHTSTAGE_HAVE_V4L2
ProbeReport probe_v4l2() { return {"v4l2", false, {}, "built without V4L2 headers"}; }
#endif
#ifndef LIGHTSTAGE_HAVE_LIBCAMERA
ProbeReport probe_libcamera() { return {"libcamera", false, {}, "built without libcamera"}; }
#endif
#ifndef LIGHTSTAGE_HAVE_ARAVIS
ProbeReport probe_aravis() { return {"aravis", false, {}, "built without aravis"}; }
#endif
#ifndef LIGHTSTAGE_HAVE_GPHOTO2
ProbeReport probe_gphoto2() { return {"gphoto2", false, {}, "built without libgphoto2"}; }
#endif
#ifndef LIGHTSTAGE_HAVE_LIBUSB
ProbeReport probe_usb() { return {"usb", false, {}, "built without libusb"}; }
#endif

}  // namespace lightstage::hw
