#pragma once
// Geometry shared by every module. Frames follow ARCHITECTURE.md: camera frame
// x right, y up, z toward the camera; the viewer is v = (0,0,1); light
// directions point from the object to the light. The dome frame has the same
// axes as the camera frame (the camera looks straight down the dome axis) with
// its origin at the dome centre; lengths are millimetres.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cmath>
#include <numbers>

namespace lightstage {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

inline constexpr double kPi = std::numbers::pi;

inline double deg_from_rad(double rad) { return rad * 180.0 / kPi; }
inline double rad_from_deg(double deg) { return deg * kPi / 180.0; }

// Angle between two directions in degrees; robust near 0 and 180 degrees
// (atan2 of sine and cosine rather than acos of a clamped dot product).
inline double angle_between_deg(const Vec3& a, const Vec3& b) {
  return deg_from_rad(std::atan2(a.cross(b).norm(), a.dot(b)));
}

// Unit direction from elevation (from the image plane, towards +z) and azimuth
// (from +x towards +y), as in ALGORITHMS.md §2: n = [cosθ cosφ, cosθ sinφ, sinθ].
inline Vec3 direction_from_elevation_azimuth(double elevation_rad, double azimuth_rad) {
  return {std::cos(elevation_rad) * std::cos(azimuth_rad), std::cos(elevation_rad) * std::sin(azimuth_rad),
          std::sin(elevation_rad)};
}

// Half vector between a light direction and the viewer.
inline Vec3 half_vector(const Vec3& light_dir, const Vec3& view_dir = Vec3::UnitZ()) {
  return (light_dir + view_dir).normalized();
}

}  // namespace lightstage
