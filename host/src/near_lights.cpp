#include "lightstage/host/near_lights.hpp"

#include <cmath>

namespace lightstage {

void near_light_directions(const NearLights& near, std::size_t pixel, Eigen::MatrixX3d& directions,
                           Eigen::VectorXd& gains) {
  const Eigen::Index n = near.led_positions_mm.rows();
  directions.resize(n, 3);
  gains.resize(n);
  const Eigen::RowVector3d x = near.points_mm.row(static_cast<Eigen::Index>(pixel));
  for (Eigen::Index j = 0; j < n; ++j) {
    const Eigen::RowVector3d to_led = near.led_positions_mm.row(j) - x;
    const double d = to_led.norm();
    const double d0 = (near.led_positions_mm.row(j) - near.object_centre_mm.transpose()).norm();
    directions.row(j) = to_led / d;
    gains(j) = (d0 * d0) / (d * d);
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
