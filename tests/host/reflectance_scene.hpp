#pragma once
// Synthetic data for the general-reflectance tests: a grid of normals over
// the visible hemisphere seen under random distant lights (the material
// sweep's renderer, pipeline/synthetic_observations.hpp) or near LEDs of the
// sim dome, shaded exactly by a sim BRDF. Small on purpose (the tests
// also run under sanitizers); the big sweeps live in `lightstage bench materials`.

#include "lightstage/common/geometry.hpp"
#include "lightstage/common/rig.hpp"
#include "lightstage/host/eval/angular_error.hpp"
#include "lightstage/host/near_lights.hpp"
#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/solvers/solve_result.hpp"
#include "lightstage/pipeline/synthetic_observations.hpp"
#include "lightstage/sim/material.hpp"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <cmath>
#include <random>
#include <string>

namespace lightstage::testing {

using ReflectanceScene = pipeline::SyntheticScene;

// Mean angular error of `result` against the scene's truth; every pixel must be solved.
inline double mean_error(const SolveResult& result, const ReflectanceScene& scene) {
  const auto stats = angular_error(result.normals, scene.truth, scene.observations.mask).stats;
  EXPECT_EQ(stats.missing, 0u) << result.summary.message;
  return stats.mean;
}

inline Eigen::MatrixX3d hemisphere_lights(int count, unsigned seed, double min_z = 0.1) {
  return pipeline::random_hemisphere_lights(count, min_z, seed);
}

// width × height normals: azimuth over columns, elevation 15°..88° over rows.
inline Vec3 grid_normal(int x, int y, int width, int height) {
  const double azimuth = 2 * kPi * (x + 0.5) / width;
  const double elevation = rad_from_deg(15 + 73.0 * (y + 0.5) / height);
  return direction_from_elevation_azimuth(elevation, azimuth);
}

// Distant lights; `noise` = λ of y + λ y X with 16-bit quantisation (< 0: exact).
inline ReflectanceScene make_reflectance_scene(const std::string& material_preset,
                                               const Eigen::MatrixX3d& lights, int width = 12, int height = 8,
                                               double noise = -1, unsigned seed = 3) {
  pipeline::SyntheticOptions options;
  options.scale = 0.5;
  options.noise = noise;
  options.seed = seed;
  return pipeline::render_synthetic(
      sim::parse_material(material_preset), cv::Size(width, height),
      [width, height](int x, int y) { return grid_normal(x, y, width, height); }, lights, options);
}

// The sim dome's LEDs as near point lights over a small patch of surface
// points on the plane z = 0 (± 20 mm around the centre): every pixel sees
// its own light directions and 1/d² falloff.
inline ReflectanceScene make_near_scene(const std::string& material_preset, const Rig& rig, int width = 8,
                                        int height = 6) {
  const sim::Material material = sim::parse_material(material_preset);
  ReflectanceScene scene;
  Observations& obs = scene.observations;
  const auto images = static_cast<Eigen::Index>(rig.leds.size());
  NearLights near;
  near.led_positions_mm.resize(images, 3);
  for (Eigen::Index j = 0; j < images; ++j)
    near.led_positions_mm.row(j) = rig.leds[static_cast<std::size_t>(j)].position_mm.transpose();
  near.object_centre_mm = rig.object_position_mm;
  obs.size = cv::Size(width, height);
  obs.mask = cv::Mat(obs.size, CV_8UC1, cv::Scalar::all(255));
  obs.lights.resize(images, 3);
  for (Eigen::Index j = 0; j < images; ++j) obs.lights.row(j) = near.led_positions_mm.row(j).normalized();
  const int pixels = width * height;
  near.points_mm.resize(pixels, 3);
  obs.intensities.resize(pixels, images);
  obs.saturated = FlagMatrix::Constant(pixels, images, false);
  scene.truth = cv::Mat(obs.size, CV_32FC3);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const int p = static_cast<int>(obs.pixels.size());
      obs.pixels.emplace_back(x, y);
      const Vec3 point(-20 + 40.0 * x / std::max(1, width - 1), -20 + 40.0 * y / std::max(1, height - 1), 0);
      near.points_mm.row(p) = point.transpose();
      const Vec3 n = grid_normal(x, y, width, height);
      scene.truth.at<cv::Vec3f>(y, x) =
          cv::Vec3f(static_cast<float>(n.x()), static_cast<float>(n.y()), static_cast<float>(n.z()));
      for (Eigen::Index j = 0; j < images; ++j) {
        const Vec3 to_led = near.led_positions_mm.row(j).transpose() - point;
        const double d0 = (near.led_positions_mm.row(j).transpose() - near.object_centre_mm).norm();
        const double gain = d0 * d0 / to_led.squaredNorm();
        obs.intensities(p, j) =
            static_cast<float>(0.5 * gain * material.shading(0, 0, n, to_led.normalized(), Vec3::UnitZ()));
      }
    }
  }
  obs.near = near;
  return scene;
}

}  // namespace lightstage::testing
