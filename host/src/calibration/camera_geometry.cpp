#include "lightstage/host/calibration/camera_geometry.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/printable.hpp"

#include <algorithm>
#include <cmath>

namespace lightstage::calibration {
namespace {

using nlohmann::json;

double number_at(const json& j, const char* key, const std::string& where) {
  const auto it = j.find(key);
  if (it == j.end()) fail("{}.{}: missing", where, key);
  if (!it->is_number()) fail("{}.{}: expected a number, got {}", where, key, printable(it->dump()));
  const double value = it->get<double>();
  if (!std::isfinite(value)) fail("{}.{}: not a finite number", where, key);
  return value;
}

Vec3 vec3_at(const json& j, const char* key, const std::string& where) {
  const auto it = j.find(key);
  if (it == j.end()) fail("{}.{}: missing", where, key);
  if (!it->is_array() || it->size() != 3 || !(*it)[0].is_number() || !(*it)[1].is_number() ||
      !(*it)[2].is_number()) {
    fail("{}.{}: expected [x, y, z], got {}", where, key, printable(it->dump()));
  }
  const Vec3 v((*it)[0].get<double>(), (*it)[1].get<double>(), (*it)[2].get<double>());
  if (!v.allFinite()) fail("{}.{}: not finite", where, key);
  return v;
}

}  // namespace

void CameraGeometry::ray(const Vec2& uv, Vec3* origin, Vec3* direction) const {
  if (model == CameraModel::kOrthographic) {
    const double x = (uv.x() - width / 2.0) * pixel_pitch_mm;
    const double y = (height / 2.0 - uv.y()) * pixel_pitch_mm;
    *origin = Vec3(position_mm.x() + x, position_mm.y() + y, position_mm.z());
    *direction = -Vec3::UnitZ();
    return;
  }
  *origin = position_mm;
  *direction =
      Vec3((uv.x() - principal_point_px.x()) / focal_px, (principal_point_px.y() - uv.y()) / focal_px, -1.0)
          .normalized();
}

std::optional<Vec2> CameraGeometry::project(const Vec3& point_mm) const {
  const Vec3 d = point_mm - position_mm;
  if (model == CameraModel::kOrthographic)
    return Vec2(d.x() / pixel_pitch_mm + width / 2.0, height / 2.0 - d.y() / pixel_pitch_mm);
  if (!(-d.z() > 0)) return std::nullopt;
  return Vec2(principal_point_px.x() + focal_px * d.x() / -d.z(),
              principal_point_px.y() - focal_px * d.y() / -d.z());
}

Vec3 CameraGeometry::toward_camera(const Vec3& point_mm) const {
  if (model == CameraModel::kOrthographic) return Vec3::UnitZ();
  return (position_mm - point_mm).normalized();
}

void CameraGeometry::check() const {
  if (width <= 0 || height <= 0) fail("camera: size must be positive, got {}x{}", width, height);
  if (model == CameraModel::kOrthographic && !(pixel_pitch_mm > 0 && std::isfinite(pixel_pitch_mm)))
    fail("camera.pixel_pitch_mm: must be positive, got {}", pixel_pitch_mm);
  if (model == CameraModel::kPinhole && !(focal_px > 0 && std::isfinite(focal_px)))
    fail("camera.focal_px: a pinhole camera needs a positive focal length, got {}", focal_px);
  if (!position_mm.allFinite() || !principal_point_px.allFinite())
    fail("camera: position and principal point must be finite");
}

json CameraGeometry::to_json() const {
  json j{{"model", model == CameraModel::kOrthographic ? "orthographic" : "pinhole"},
         {"width", width},
         {"height", height},
         {"position_mm", {position_mm.x(), position_mm.y(), position_mm.z()}},
         {"metric", metric}};
  if (model == CameraModel::kOrthographic) {
    j["pixel_pitch_mm"] = pixel_pitch_mm;
  } else {
    j["focal_px"] = focal_px;
    j["principal_point_px"] = {principal_point_px.x(), principal_point_px.y()};
  }
  return j;
}

CameraGeometry CameraGeometry::from_json(const json& j, const std::string& where) {
  if (!j.is_object()) fail("{}: expected an object, got {}", where, j.type_name());
  CameraGeometry camera;
  const auto model = j.find("model");
  if (model == j.end() || !model->is_string())
    fail("{}.model: expected \"orthographic\" or \"pinhole\"", where);
  if (model->get<std::string>() == "orthographic") {
    camera.model = CameraModel::kOrthographic;
  } else if (model->get<std::string>() == "pinhole") {
    camera.model = CameraModel::kPinhole;
  } else {
    fail("{}.model: expected \"orthographic\" or \"pinhole\", got {}", where, printable(model->dump()));
  }
  const double width = number_at(j, "width", where), height = number_at(j, "height", where);
  if (width < 1 || height < 1 || width > 65536 || height > 65536 || width != std::floor(width) ||
      height != std::floor(height)) {
    fail("{}: width and height must be whole numbers in 1..65536, got {} x {}", where, width, height);
  }
  camera.width = static_cast<int>(width);
  camera.height = static_cast<int>(height);
  camera.position_mm = vec3_at(j, "position_mm", where);
  camera.principal_point_px = Vec2(camera.width / 2.0, camera.height / 2.0);
  if (camera.model == CameraModel::kOrthographic) {
    camera.pixel_pitch_mm = number_at(j, "pixel_pitch_mm", where);
  } else {
    camera.focal_px = number_at(j, "focal_px", where);
    if (const auto pp = j.find("principal_point_px"); pp != j.end()) {
      if (!pp->is_array() || pp->size() != 2 || !(*pp)[0].is_number() || !(*pp)[1].is_number())
        fail("{}.principal_point_px: expected [u, v], got {}", where, printable(pp->dump()));
      camera.principal_point_px = Vec2((*pp)[0].get<double>(), (*pp)[1].get<double>());
    }
  }
  camera.metric = true;
  if (const auto metric = j.find("metric"); metric != j.end()) {
    if (!metric->is_boolean())
      fail("{}.metric: expected true or false, got {}", where, printable(metric->dump()));
    camera.metric = metric->get<bool>();
  }
  try {
    camera.check();
  } catch (const InputError& e) {
    fail("{}: {}", where, e.what());
  }
  return camera;
}

CameraGeometry CameraGeometry::from_rig(const CameraDefaults& rig_camera, int width, int height) {
  CameraGeometry camera;
  camera.model = rig_camera.model;
  camera.width = width;
  camera.height = height;
  // Same rule as the simulator's make_camera: square pixels, the field of view fitted.
  const double shrink = std::min(static_cast<double>(width) / rig_camera.width,
                                 static_cast<double>(height) / rig_camera.height);
  camera.pixel_pitch_mm = rig_camera.pixel_pitch_mm / shrink;
  camera.focal_px = rig_camera.focal_px * shrink;
  camera.principal_point_px = Vec2(width / 2.0, height / 2.0);
  camera.position_mm = rig_camera.position_mm;
  camera.metric = true;
  camera.check();
  return camera;
}

CameraGeometry CameraGeometry::unknown(int width, int height) {
  CameraGeometry camera;
  camera.width = width;
  camera.height = height;
  camera.pixel_pitch_mm = 1.0;
  camera.principal_point_px = Vec2(width / 2.0, height / 2.0);
  camera.metric = false;
  return camera;
}

}  // namespace lightstage::calibration
