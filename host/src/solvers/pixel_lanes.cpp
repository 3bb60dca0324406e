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

// Each image's observed values and unsaturated flags of four rows, each
// image's lanes made in registers and stored whole: stored lane by lane, the
// vector loads that read them back could not take them from the stores.
LIGHTSTAGE_SIMD_CLONES void gather_rows(const float* const* values, const bool* const* saturated,
                                        std::size_t images, PixelLanes* observed, PixelLanes* unsaturated) {
  static_assert(kPixelLanes == 4);
  const float *v0 = values[0], *v1 = values[1], *v2 = values[2], *v3 = values[3];
  for (std::size_t j = 0; j < images; ++j) observed[j] = PixelLanes{v0[j], v1[j], v2[j], v3[j]};
  if (saturated == nullptr) {
    for (std::size_t j = 0; j < images; ++j) unsaturated[j] = PixelLanes{} + 1.0;
    return;
  }
  const bool *s0 = saturated[0], *s1 = saturated[1], *s2 = saturated[2], *s3 = saturated[3];
  for (std::size_t j = 0; j < images; ++j)
    unsaturated[j] = 1.0 - PixelLanes{static_cast<double>(s0[j]), static_cast<double>(s1[j]),
                                      static_cast<double>(s2[j]), static_cast<double>(s3[j])};
}

}  // namespace

void load_light_lanes(const Observations& observations, const Eigen::VectorXd& reference,
                      const std::size_t* pixels, std::size_t count, LightLanes& out) {
  const auto images = static_cast<std::size_t>(observations.intensities.cols());
  out.used = count;
  out.observed.resize(images);
  out.unsaturated.resize(images);
  out.x.resize(images);
  out.y.resize(images);
  out.z.resize(images);
  std::size_t rows[kPixelLanes];  // lanes past `count` repeat the first pixel
  const float* values[kPixelLanes];
  const bool* saturated[kPixelLanes];
  const bool flags = observations.saturated.size() != 0;
  for (std::size_t lane = 0; lane < kPixelLanes; ++lane) {
    rows[lane] = pixels[lane < count ? lane : 0];
    const auto row = static_cast<Eigen::Index>(rows[lane]);
    values[lane] = observations.intensities.row(row).data();
    saturated[lane] = flags ? observations.saturated.row(row).data() : nullptr;
  }
  gather_rows(values, flags ? saturated : nullptr, images, out.observed.data(), out.unsaturated.data());
  if (!observations.near) {
    // The same for every pixel: filled once.
    if (out.distant_lights == observations.lights.data()) return;
    out.gain.clear();
    const Eigen::MatrixX3d& lights = observations.lights;
    for (std::size_t j = 0; j < images; ++j) {
      const auto i = static_cast<Eigen::Index>(j);
      out.x[j] = lights(i, 0) - PixelLanes{};
      out.y[j] = lights(i, 1) - PixelLanes{};
      out.z[j] = lights(i, 2) - PixelLanes{};
    }
    out.distant_lights = lights.data();
    return;
  }
  const NearLights& near = *observations.near;
  out.distant_lights = nullptr;
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
