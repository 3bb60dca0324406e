#include "lightstage/host/near_lights.hpp"

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

}  // namespace lightstage
