#pragma once
// Synthetic photometric-stereo data for the host tests: random normals on the
// upper hemisphere, random lights, exact Lambertian shading. "Exact" is meant
// literally: light components are multiples of 1/64 and the scaled normals
// s = albedo · n multiples of 1/256, so every shading value L s is a float
// without rounding and a solver working in double recovers s to ~1e-15.

#include "lightstage/common/geometry.hpp"
#include "lightstage/host/radiometry.hpp"

#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace lightstage::testing {

inline Vec3 quantised(const Vec3& v, double step) { return (v / step).array().round().matrix() * step; }

inline Vec3 random_upper_direction(std::mt19937& rng, double min_z = 0.1) {
  std::normal_distribution<double> gauss;
  for (;;) {
    Vec3 v(gauss(rng), gauss(rng), gauss(rng));
    if (v.norm() < 1e-6) continue;
    v.normalize();
    if (v.z() < 0) v.z() = -v.z();
    if (v.z() >= min_z) return v;
  }
}

// `count` lights with z uniform in [min_z, 1] and uniform azimuth (the RTI tests' domes).
inline Eigen::MatrixX3d uniform_z_lights(int count, unsigned seed, double min_z) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  Eigen::MatrixX3d l(count, 3);
  for (int i = 0; i < count; ++i) {
    const double z = min_z + (1 - min_z) * u(rng), phi = 2 * M_PI * u(rng), r = std::sqrt(1 - z * z);
    l.row(i) << r * std::cos(phi), r * std::sin(phi), z;
  }
  return l;
}

struct SyntheticScene {
  Observations observations;
  std::vector<Vec3> normals;   // per observation row, unit
  std::vector<double> albedo;  // per observation row
};

// `width` × `height` pixels, all inside the mask, `images` lights. With
// `clamp_shadows`, shading is max(0, n·l) (attached shadows); otherwise n·l
// may go negative (the pure linear model).
inline SyntheticScene make_scene(int width, int height, int images, unsigned seed, bool clamp_shadows) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> albedo_dist(0.2, 0.9);
  SyntheticScene scene;
  Observations& obs = scene.observations;
  obs.size = cv::Size(width, height);
  obs.mask = cv::Mat(obs.size, CV_8UC1, cv::Scalar::all(255));
  obs.lights.resize(images, 3);
  // Near-unit lights on the 1/64 grid (the solver does not need unit lights).
  for (int j = 0; j < images; ++j)
    obs.lights.row(j) = quantised(random_upper_direction(rng, 0.3), 1.0 / 64).transpose();
  const int pixels = width * height;
  obs.intensities.resize(pixels, images);
  obs.saturated = FlagMatrix::Constant(pixels, images, false);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const int p = static_cast<int>(obs.pixels.size());
      obs.pixels.emplace_back(x, y);
      const Vec3 s = quantised(albedo_dist(rng) * random_upper_direction(rng, 0.05), 1.0 / 256);
      scene.normals.push_back(s.normalized());
      scene.albedo.push_back(s.norm());
      for (int j = 0; j < images; ++j) {
        double shade = obs.lights.row(j).dot(s);
        if (clamp_shadows) shade = std::max(shade, 0.0);
        obs.intensities(p, j) = static_cast<float>(shade);
      }
    }
  }
  return scene;
}

}  // namespace lightstage::testing
