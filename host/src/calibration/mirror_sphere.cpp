#include "lightstage/host/calibration/mirror_sphere.hpp"

#include "lightstage/common/error.hpp"

#include <cmath>

namespace lightstage::calibration {

nlohmann::json MirrorSphere::to_json() const {
  return {{"circle", circle.to_json()},
          {"centre_mm", {centre_mm.x(), centre_mm.y(), centre_mm.z()}},
          {"radius_mm", radius_mm}};
}

MirrorSphere locate_sphere(const ImageCircle& circle, const CameraGeometry& camera, double centre_z_mm,
                           double radius_mm) {
  MirrorSphere sphere;
  sphere.circle = circle;
  Vec3 origin, dir;
  camera.ray(circle.centre_px, &origin, &dir);
  if (camera.model == CameraModel::kOrthographic) {
    sphere.radius_mm = circle.radius_px * camera.pixel_pitch_mm;
    sphere.centre_mm = Vec3(origin.x(), origin.y(), centre_z_mm);
    return sphere;
  }
  if (!(radius_mm > 0)) fail("pinhole camera: the sphere's radius in mm must be given, got {}", radius_mm);
  // Half-angle of the cone tangent to the sphere: the mean angle to rays through the outline.
  double half_angle = 0;
  constexpr int kSamples = 32;
  for (int k = 0; k < kSamples; ++k) {
    const double a = 2 * kPi * k / kSamples;
    Vec3 o, d;
    camera.ray(circle.centre_px + circle.radius_px * Vec2(std::cos(a), std::sin(a)), &o, &d);
    half_angle += std::atan2(dir.cross(d).norm(), dir.dot(d));
  }
  half_angle /= kSamples;
  sphere.radius_mm = radius_mm;
  sphere.centre_mm = origin + dir * (radius_mm / std::sin(half_angle));
  return sphere;
}

std::optional<Reflection> reflect_at(const MirrorSphere& sphere, const CameraGeometry& camera,
                                     const Vec2& uv) {
  Vec3 origin, dir;
  camera.ray(uv, &origin, &dir);
  // |o + t d − c|² = r²  →  t² + 2 t d·(o − c) + |o − c|² − r² = 0
  const Vec3 oc = origin - sphere.centre_mm;
  const double b = dir.dot(oc);
  const double disc = b * b - (oc.squaredNorm() - sphere.radius_mm * sphere.radius_mm);
  if (disc < 0) return std::nullopt;
  const double t = -b - std::sqrt(disc);
  Reflection reflection;
  reflection.point_mm = origin + t * dir;
  reflection.normal = (reflection.point_mm - sphere.centre_mm).normalized();
  const Vec3 view = -dir;
  reflection.direction = (2 * reflection.normal.dot(view) * reflection.normal - view).normalized();
  return reflection;
}

}  // namespace lightstage::calibration
