#include "lightstage/host/solvers/pixel_observations.hpp"

#include "lightstage/common/error.hpp"

#include <cmath>

namespace lightstage {

void check_observations(const Observations& observations, const char* who) {
  const auto pixels = static_cast<Eigen::Index>(observations.pixel_count());
  const auto images = static_cast<Eigen::Index>(observations.image_count());
  if (observations.intensities.rows() != pixels || observations.intensities.cols() != images) {
    fail("{}: observations are {}x{}, expected {} pixels x {} images", who, observations.intensities.rows(),
         observations.intensities.cols(), pixels, images);
  }
  if (observations.saturated.size() != 0 &&
      (observations.saturated.rows() != pixels || observations.saturated.cols() != images)) {
    fail("{}: saturation flags are {}x{}, expected {} pixels x {} images", who, observations.saturated.rows(),
         observations.saturated.cols(), pixels, images);
  }
  if (observations.near) {
    if (observations.near->led_positions_mm.rows() != images)
      fail("{}: near lights hold {} LED positions for {} images", who,
           observations.near->led_positions_mm.rows(), images);
    if (observations.near->points_mm.rows() != pixels)
      fail("{}: near lights hold {} surface points for {} pixels", who, observations.near->points_mm.rows(),
           pixels);
  }
}

namespace {

// load_pixel's values and usable flags, `out.lights` and `out.near_gains`
// (empty: distant) set for this pixel already.
void load_pixel_values(const Observations& observations, std::size_t pixel, bool drop_saturated,
                       PixelObservations& out) {
  const auto row = static_cast<Eigen::Index>(pixel);
  const Eigen::Index images = observations.intensities.cols();
  out.values = observations.intensities.row(row).transpose().cast<double>();
  // The LED is brighter (gain > 1) when closer: divide to get the value at unit light.
  if (out.near_lights()) out.values = out.values.cwiseQuotient(out.near_gains);
  out.usable.assign(static_cast<std::size_t>(images), 1);
  const bool flags = observations.saturated.size() != 0;
  for (Eigen::Index j = 0; j < images; ++j) {
    const bool saturated = drop_saturated && flags && observations.saturated(row, j);
    if (!std::isfinite(out.values(j)) || saturated) out.usable[static_cast<std::size_t>(j)] = 0;
  }
}

}  // namespace

void load_pixel(const Observations& observations, std::size_t pixel, bool drop_saturated,
                PixelObservations& out) {
  if (observations.near) {
    near_light_directions(*observations.near, pixel, out.lights, out.near_gains);
  } else {
    out.lights = observations.lights;
    out.near_gains.resize(0);
  }
  load_pixel_values(observations, pixel, drop_saturated, out);
}

}  // namespace lightstage
