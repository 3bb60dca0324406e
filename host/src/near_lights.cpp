#include "lightstage/host/near_lights.hpp"

#include <cmath>

namespace lightstage {

void near_light_directions(const NearLights& near, std::size_t pixel, Eigen::MatrixX3d& directions,
                           Eigen::VectorXd& gains) {
  const Eigen::Index n = near.led_positions_mm.rows();
  directions.resize(n, 3);
  gains.resize(n);
  const Eigen::MatrixX3d& leds = near.led_positions_mm;
  const Eigen::Index row = static_cast<Eigen::Index>(pixel);
  const double x = near.points_mm(row, 0), y = near.points_mm(row, 1), z = near.points_mm(row, 2);
  const Eigen::Vector3d& c = near.object_centre_mm;
  // Squared distances throughout: one square root a light (this runs for every pixel and light).
  for (Eigen::Index j = 0; j < n; ++j) {
    const double dx = leds(j, 0) - x, dy = leds(j, 1) - y, dz = leds(j, 2) - z;
    const double cx = leds(j, 0) - c.x(), cy = leds(j, 1) - c.y(), cz = leds(j, 2) - c.z();
    const double d2 = dx * dx + dy * dy + dz * dz;
    const double inverse_d = 1.0 / std::sqrt(d2);
    directions(j, 0) = dx * inverse_d;
    directions(j, 1) = dy * inverse_d;
    directions(j, 2) = dz * inverse_d;
    gains(j) = (cx * cx + cy * cy + cz * cz) / d2;
  }
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
