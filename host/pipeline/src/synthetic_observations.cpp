#include "lightstage/pipeline/synthetic_observations.hpp"

#include "lightstage/common/error.hpp"

#include <algorithm>
#include <cmath>
#include <random>

namespace lightstage::pipeline {

Eigen::MatrixX3d random_hemisphere_lights(int count, double min_z, std::uint64_t seed) {
  if (count < 1) fail("random lights: count must be positive, got {}", count);
  if (!(min_z >= 0 && min_z < 1)) fail("random lights: min_z must be in [0, 1), got {}", min_z);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss;
  Eigen::MatrixX3d lights(count, 3);
  for (int j = 0; j < count;) {
    Vec3 v(gauss(rng), gauss(rng), gauss(rng));
    if (v.norm() < 1e-9) continue;
    v.normalize();
    v.z() = std::abs(v.z());
    if (v.z() < min_z) continue;
    lights.row(j++) = v.transpose();
  }
  return lights;
}

SyntheticScene render_synthetic(const sim::Material& material, cv::Size size, const NormalGrid& normal_at,
                                const Eigen::MatrixX3d& lights, const SyntheticOptions& options) {
  if (size.width < 1 || size.height < 1) fail("synthetic scene: empty grid {}x{}", size.width, size.height);
  SyntheticScene scene;
  Observations& obs = scene.observations;
  obs.size = size;
  obs.mask = cv::Mat(size, CV_8UC1, cv::Scalar::all(255));
  obs.lights = lights;
  const auto images = lights.rows();
  const int pixels = size.area();
  obs.intensities.resize(pixels, images);
  obs.saturated = FlagMatrix::Constant(pixels, images, false);
  scene.truth = cv::Mat(size, CV_32FC3);
  Eigen::MatrixXd exact(pixels, images);
  const Vec3 view = Vec3::UnitZ();
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      const int p = y * size.width + x;
      obs.pixels.emplace_back(x, y);
      const Vec3 n = normal_at(x, y);
      scene.truth.at<cv::Vec3f>(y, x) =
          cv::Vec3f(static_cast<float>(n.x()), static_cast<float>(n.y()), static_cast<float>(n.z()));
      for (Eigen::Index j = 0; j < images; ++j)
        exact(p, j) = material.shading(0, 0, n, lights.row(j).transpose(), view);
    }
  }
  if (options.scale > 0) {
    exact *= options.scale;
  } else if (const double peak = exact.maxCoeff(); peak > 0) {
    exact /= peak;
  }
  std::mt19937_64 rng(options.seed);
  std::normal_distribution<double> gauss;
  for (int p = 0; p < pixels; ++p) {
    for (Eigen::Index j = 0; j < images; ++j) {
      double value = exact(p, j);
      if (options.noise >= 0) {
        value += options.noise * value * gauss(rng);
        if (value >= 1.0) obs.saturated(p, j) = true;
        value = std::round(std::clamp(value, 0.0, 1.0) * 65535.0) / 65535.0;
      }
      obs.intensities(p, j) = static_cast<float>(value);
    }
  }
  return scene;
}

cv::Size sweep_grid_size() { return {36, 45}; }

Vec3 sweep_grid_normal(int x, int y) {
  return direction_from_elevation_azimuth(rad_from_deg(2.0 * (y + 1)), rad_from_deg(10.0 * (x + 1)));
}

}  // namespace lightstage::pipeline
