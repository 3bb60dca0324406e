#pragma once
// A mirror sphere in 3-D and the light a highlight on it points to.
// Orthographic camera: the sphere's radius in millimetres is its image radius
// times the pixel pitch, its depth is given (the table height: an orthographic
// image cannot show it). Pinhole camera: the sphere's centre lies on the ray
// through the outline's centre, at the distance where a sphere of the given
// radius fills the outline's cone. Either way the highlight's viewing ray
// meets the sphere at x with normal n, and the light lies along the mirror
// direction l = 2(n·v)n − v, v pointing back to the camera (ALGORITHMS.md §5).

#include "lightstage/host/calibration/camera_geometry.hpp"
#include "lightstage/host/calibration/sphere_detection.hpp"

#include <nlohmann/json.hpp>

#include <optional>

namespace lightstage::calibration {

struct MirrorSphere {
  ImageCircle circle;
  Vec3 centre_mm = Vec3::Zero();  // dome frame
  double radius_mm = 0;

  nlohmann::json to_json() const;
};

// Places `circle` in 3-D. Orthographic: `centre_z_mm` is the centre's height
// (the radius follows from the pitch). Pinhole: `radius_mm` is the sphere's
// true radius (directions do not depend on it, positions do).
MirrorSphere locate_sphere(const ImageCircle& circle, const CameraGeometry& camera, double centre_z_mm,
                           double radius_mm);

struct Reflection {
  Vec3 point_mm;   // where the viewing ray meets the sphere
  Vec3 normal;     // unit, outward
  Vec3 direction;  // unit, from the point toward the light
};

// The reflection at image point `uv`; nullopt when its ray misses the sphere.
std::optional<Reflection> reflect_at(const MirrorSphere& sphere, const CameraGeometry& camera,
                                     const Vec2& uv);

}  // namespace lightstage::calibration
