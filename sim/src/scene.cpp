#include "lightstage/sim/scene.hpp"

#include "lightstage/common/error.hpp"

#include <algorithm>

namespace lightstage::sim {

nlohmann::json Scene::describe() const {
  nlohmann::json j{{"name", name},
                   {"object", shape ? shape->describe() : nlohmann::json()},
                   {"material", material.describe()},
                   {"led_radius_mm", led_radius_mm},
                   {"led_radiance", led_radiance},
                   {"highlight_blur_px", highlight_blur_px},
                   {"environment_radiance", environment_radiance},
                   {"cast_shadows", cast_shadows}};
  return j;
}

void Camera::ray(double u, double v, Vec3* origin, Vec3* dir) const {
  const double cu = u - width / 2.0;
  const double cv = height / 2.0 - v;
  if (model == CameraModel::kOrthographic) {
    *origin =
        Vec3(position_mm.x() + cu * pixel_pitch_mm, position_mm.y() + cv * pixel_pitch_mm, position_mm.z());
    *dir = -Vec3::UnitZ();
  } else {
    *origin = position_mm;
    *dir = Vec3(cu / focal_px, cv / focal_px, -1.0).normalized();
  }
}

nlohmann::json Camera::describe() const {
  nlohmann::json j{{"model", model == CameraModel::kOrthographic ? "orthographic" : "pinhole"},
                   {"width", width},
                   {"height", height},
                   {"position_mm", {position_mm.x(), position_mm.y(), position_mm.z()}}};
  if (model == CameraModel::kOrthographic) {
    j["pixel_pitch_mm"] = pixel_pitch_mm;
  } else {
    j["focal_px"] = focal_px;
  }
  return j;
}

Camera make_camera(const CameraDefaults& rig_camera, const CameraOverrides& scene, std::optional<int> width,
                   std::optional<int> height) {
  Camera cam;
  cam.model = scene.model.value_or(rig_camera.model);
  cam.width = scene.width.value_or(rig_camera.width);
  cam.height = scene.height.value_or(rig_camera.height);
  cam.pixel_pitch_mm = scene.pixel_pitch_mm.value_or(rig_camera.pixel_pitch_mm);
  cam.focal_px = scene.focal_px.value_or(rig_camera.focal_px);
  cam.position_mm = scene.position_mm.value_or(rig_camera.position_mm);
  if (width || height) {
    const int w = width.value_or(height ? *height * cam.width / std::max(cam.height, 1) : cam.width);
    const int h = height.value_or(width ? *width * cam.height / std::max(cam.width, 1) : cam.height);
    if (w <= 0 || w > 16384) fail("camera width must be in 1..16384, got {}", w);
    if (h <= 0 || h > 16384) fail("camera height must be in 1..16384, got {}", h);
    const double shrink = std::min(static_cast<double>(w) / cam.width, static_cast<double>(h) / cam.height);
    cam.pixel_pitch_mm /= shrink;
    cam.focal_px *= shrink;
    cam.width = w;
    cam.height = h;
  }
  if (cam.width <= 0 || cam.height <= 0)
    fail("camera size must be positive, got {}x{}", cam.width, cam.height);
  if (cam.model == CameraModel::kOrthographic && !(cam.pixel_pitch_mm > 0)) {
    fail("camera pixel_pitch_mm must be positive, got {}", cam.pixel_pitch_mm);
  }
  if (cam.model == CameraModel::kPinhole && !(cam.focal_px > 0)) {
    fail("pinhole camera needs a positive focal_px, got {}", cam.focal_px);
  }
  return cam;
}

}  // namespace lightstage::sim
