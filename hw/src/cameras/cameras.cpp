// The hardware camera schemes, registered with common/camera.hpp's registry.
#include "lightstage/hw/cameras.hpp"

#include <mutex>

namespace lightstage::hw {

#ifndef LIGHTSTAGE_HAVE_V4L2
camera::CameraScheme v4l2_camera_scheme() {
  return {"v4l2",
          "v4l2:/dev/videoN",
          "this build has no V4L2 backend (it was built without linux/videodev2.h)",
          {},
          {}};
}
#endif
#ifndef LIGHTSTAGE_HAVE_LIBCAMERA
camera::CameraScheme libcamera_camera_scheme() {
  return {"libcamera",
          "libcamera:ID",
          "this build has no libcamera backend (install libcamera-dev and rebuild)",
          {},
          {}};
}
#endif

void register_hw_cameras() {
  static std::once_flag once;
  std::call_once(once, [] {
    camera::register_camera_scheme(v4l2_camera_scheme());
    camera::register_camera_scheme(libcamera_camera_scheme());
  });
}

std::unique_ptr<camera::Camera> open_camera(const std::string& uri) {
  register_hw_cameras();
  return camera::open_camera_uri(uri);
}

std::vector<camera::CameraInfo> list_cameras() {
  register_hw_cameras();
  std::vector<camera::CameraInfo> found;
  for (const auto& scheme : camera::camera_schemes()) {
    if (!scheme.unavailable.empty() || !scheme.list) continue;
    try {
      for (auto& info : scheme.list()) found.push_back(std::move(info));
    } catch (const std::exception&) {
      // A scheme that cannot enumerate (no camera manager) lists nothing.
    }
  }
  return found;
}

}  // namespace lightstage::hw
