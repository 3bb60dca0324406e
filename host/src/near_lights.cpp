#include "lightstage/host/near_lights.hpp"

#include <cmath>

namespace lightstage {

namespace {

// The unit directions, and in `squared` each LED's squared distance from the pixel's point.
void directions_and_distances(const NearLights& near, std::size_t pixel, Eigen::MatrixX3d& directions,
                              Eigen::VectorXd& squared) {
  const Eigen::Index n = near.led_positions_mm.rows();
  directions.resize(n, 3);
  squared.resize(n);
  const Eigen::MatrixX3d& leds = near.led_positions_mm;
  const Eigen::Index row = static_cast<Eigen::Index>(pixel);
  // Whole columns at a time (SIMD lanes of lights), squared distances throughout: one square root a light
  // (this runs for every pixel and light).
  const auto dx = leds.col(0).array() - near.points_mm(row, 0);
  const auto dy = leds.col(1).array() - near.points_mm(row, 1);
  const auto dz = leds.col(2).array() - near.points_mm(row, 2);
  squared = dx * dx + dy * dy + dz * dz;
  directions.col(2) = squared.array().sqrt().inverse();  // 1 / d, until the line below
  directions.col(0) = dx * directions.col(2).array();
  directions.col(1) = dy * directions.col(2).array();
  directions.col(2).array() *= dz;
}

// |p_j − c|² for every LED into `out`, in storage it already has when sized.
void reference_distances(const NearLights& near, Eigen::VectorXd& out) {
  const Eigen::MatrixX3d& leds = near.led_positions_mm;
  const Eigen::Vector3d& c = near.object_centre_mm;
  const auto cx = leds.col(0).array() - c.x(), cy = leds.col(1).array() - c.y(),
             cz = leds.col(2).array() - c.z();
  out = cx * cx + cy * cy + cz * cz;
}

}  // namespace

Eigen::VectorXd near_light_reference(const NearLights& near) {
  Eigen::VectorXd reference;
  reference_distances(near, reference);
  return reference;
}

void near_light_directions(const NearLights& near, std::size_t pixel, Eigen::MatrixX3d& directions,
                           Eigen::VectorXd& gains) {
  // Kept from call to call: a caller pixel by pixel allocates nothing.
  thread_local Eigen::VectorXd reference;
  reference_distances(near, reference);
  directions_and_distances(near, pixel, directions, gains);
  gains = reference.array() / gains.array();
}

Eigen::MatrixX3d points_on_plane(const std::vector<cv::Point>& pixels, const PixelRay& ray, double plane_z_mm,
                                 cv::Point origin) {
  Eigen::MatrixX3d points(static_cast<Eigen::Index>(pixels.size()), 3);
  for (std::size_t p = 0; p < pixels.size(); ++p) {
    Eigen::Vector3d start, direction;
    const cv::Point at = pixels[p] + origin;
    ray(Eigen::Vector2d(at.x + 0.5, at.y + 0.5), &start, &direction);
    // A ray parallel to the plane (never for a camera looking at the object) keeps its origin's x, y.
    const double t = std::abs(direction.z()) > 1e-12 ? (plane_z_mm - start.z()) / direction.z() : 0.0;
    points.row(static_cast<Eigen::Index>(p)) = (start + t * direction).transpose();
    if (std::abs(direction.z()) <= 1e-12) points(static_cast<Eigen::Index>(p), 2) = plane_z_mm;
  }
  return points;
}

}  // namespace lightstage
