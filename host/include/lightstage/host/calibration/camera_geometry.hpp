#pragma once
// The camera as light calibration sees it: a viewing ray for every image
// point, in the dome frame (camera axes, millimetres; geometry.hpp). Image
// points (u, v) are pixels, u right and v down, with pixel (col, row) centred
// at (col + 0.5, row + 0.5) — the simulator's convention, so sub-pixel
// positions need no half-pixel shifts anywhere else.

#include "lightstage/common/geometry.hpp"
#include "lightstage/common/rig.hpp"

#include <nlohmann/json.hpp>

#include <optional>
#include <string>

namespace lightstage::calibration {

struct CameraGeometry {
  CameraModel model = CameraModel::kOrthographic;
  int width = 0;
  int height = 0;
  double pixel_pitch_mm = 1.0;             // orthographic: millimetres per pixel at the object
  double focal_px = 0;                     // pinhole: focal length in pixels
  Vec2 principal_point_px = Vec2::Zero();  // pinhole: where the optical axis meets the image
  Vec3 position_mm = Vec3(0, 0, 1000);     // pinhole centre / a point on the orthographic axis
  // False when nothing told us the scale (no rig, no manifest): lengths are
  // then in pixels and only directions mean anything.
  bool metric = false;

  // The viewing ray through image point (u, v): origin and unit direction (toward the scene).
  void ray(const Vec2& uv, Vec3* origin, Vec3* direction) const;
  // The image point of `point_mm` (the inverse of ray); nullopt when it lies
  // behind a pinhole camera.
  std::optional<Vec2> project(const Vec3& point_mm) const;
  // Unit vector from `point_mm` back toward the camera (along the viewing ray).
  Vec3 toward_camera(const Vec3& point_mm) const;
  // Throws InputError naming the broken field.
  void check() const;
  nlohmann::json to_json() const;
  // Reads what to_json writes (and the simulator's manifest "camera" entry);
  // `where` names the file and key in messages.
  static CameraGeometry from_json(const nlohmann::json& j, const std::string& where);
  // The rig's camera for images of width × height, keeping its field of view
  // (the pitch or focal length scales) as `lightstage simulate --width` does.
  static CameraGeometry from_rig(const CameraDefaults& rig_camera, int width, int height);
  // An orthographic camera of unknown scale (1 "mm" per pixel).
  static CameraGeometry unknown(int width, int height);
};

}  // namespace lightstage::calibration
