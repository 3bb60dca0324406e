// The hardware camera schemes, registered with common/camera.hpp's registry,
// and the stand-ins for backends this build lacks (gphoto2's too).
#include "lightstage/hw/cameras.hpp"
#include "lightstage/hw/gphoto2_source.hpp"

#include <fmt/format.h>

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
#ifndef LIGHTSTAGE_HAVE_ARAVIS
camera::CameraScheme aravis_camera_scheme() {
  return {"aravis",
          "aravis:DEVICE_ID",
          "this build has no aravis backend (install libaravis-dev and rebuild)",
          {},
          {}};
}
#endif
#ifndef LIGHTSTAGE_HAVE_GPHOTO2
std::vector<camera::CameraInfo> list_gphoto2_cameras() { return {}; }

std::unique_ptr<camera::ShotSource> open_gphoto2_source(const camera::CameraUri& uri,
                                                        const std::filesystem::path&) {
  throw camera::CameraError(
      camera::CameraError::Kind::kUnsupported,
      fmt::format("{}: this build has no gphoto2 backend (install libgphoto2-dev and rebuild)", uri.uri));
}
#endif

void register_hw_cameras() {
  static std::once_flag once;
  std::call_once(once, [] {
    camera::register_camera_scheme(v4l2_camera_scheme());
    camera::register_camera_scheme(libcamera_camera_scheme());
    camera::register_camera_scheme(aravis_camera_scheme());
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
