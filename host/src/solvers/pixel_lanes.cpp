#include "solvers/pixel_lanes.hpp"

#include "lightstage/common/simd_clones.hpp"

#include <cmath>

namespace lightstage {
namespace {

// Every image's direction and gain for the points (px, py, pz), as
// near_light_directions computes them for one pixel: squared distances, one
// square root a light.
LIGHTSTAGE_SIMD_CLONES void near_directions(const double* led_x, const double* led_y, const double* led_z,
                                            const double* reference, std::size_t images, const PixelLanes& px,
                                            const PixelLanes& py, const PixelLanes& pz, PixelLanes* x,
                                            PixelLanes* y, PixelLanes* z, PixelLanes* gain) {
  for (std::size_t j = 0; j < images; ++j) {
    const PixelLanes dx = led_x[j] - px, dy = led_y[j] - py, dz = led_z[j] - pz;
    const PixelLanes squared = dx * dx + dy * dy + dz * dz;
    PixelLanes distance;
    for (std::size_t lane = 0; lane < kPixelLanes; ++lane) distance[lane] = std::sqrt(squared[lane]);
    const PixelLanes inverse = 1.0 / distance;
    x[j] = dx * inverse;
    y[j] = dy * inverse;
    z[j] = inverse * dz;
    gain[j] = reference[j] / squared;
  }
}

}  // namespace

void load_light_lanes(const Observations& observations, const Eigen::VectorXd& reference,
                      const std::size_t* pixels, std::size_t count, LightLanes& out) {
  const auto images = static_cast<std::size_t>(observations.intensities.cols());
  out.pixels = count;
  out.x.resize(images);
  out.y.resize(images);
  out.z.resize(images);
  out.observed.resize(images);
  out.unsaturated.resize(images);
  std::size_t rows[kPixelLanes];
  for (std::size_t lane = 0; lane < kPixelLanes; ++lane) rows[lane] = pixels[lane < count ? lane : 0];
  const bool flags = observations.saturated.size() != 0;
  for (std::size_t lane = 0; lane < kPixelLanes; ++lane) {
    const auto row = static_cast<Eigen::Index>(rows[lane]);
    const float* values = observations.intensities.row(row).data();
    const bool* saturated = flags ? observations.saturated.row(row).data() : nullptr;
    for (std::size_t j = 0; j < images; ++j) {
      out.observed[j][lane] = static_cast<double>(values[j]);
      out.unsaturated[j][lane] = saturated != nullptr && saturated[j] ? 0.0 : 1.0;
    }
  }
  if (!observations.near) {
    out.gain.clear();
    const Eigen::MatrixX3d& lights = observations.lights;
    for (std::size_t j = 0; j < images; ++j) {
      const auto i = static_cast<Eigen::Index>(j);
      out.x[j] = PixelLanes{} + lights(i, 0);
      out.y[j] = PixelLanes{} + lights(i, 1);
      out.z[j] = PixelLanes{} + lights(i, 2);
    }
    return;
  }
  const NearLights& near = *observations.near;
  out.gain.resize(images);
  PixelLanes px, py, pz;
  for (std::size_t lane = 0; lane < kPixelLanes; ++lane) {
    const auto row = static_cast<Eigen::Index>(rows[lane]);
    px[lane] = near.points_mm(row, 0);
    py[lane] = near.points_mm(row, 1);
    pz[lane] = near.points_mm(row, 2);
  }
  near_directions(near.led_positions_mm.col(0).data(), near.led_positions_mm.col(1).data(),
                  near.led_positions_mm.col(2).data(), reference.data(), images, px, py, pz, out.x.data(),
                  out.y.data(), out.z.data(), out.gain.data());
}

}  // namespace lightstage
