#pragma once
// Synthetic observations without images: a grid of known normals shaded
// exactly by a sim BRDF under distant lights, with the dissertation's noise
// model y + λ·y·X (X ~ N(0,1)) and 16-bit quantisation (ALGORITHMS.md §2–3).
// The material sweep (material_sweep.hpp) and the solver tests render with it.

#include "lightstage/common/geometry.hpp"
#include "lightstage/host/radiometry.hpp"
#include "lightstage/sim/material.hpp"

#include <opencv2/core.hpp>

#include <cstdint>
#include <functional>

namespace lightstage::pipeline {

// `count` directions drawn uniformly on the upper hemisphere with z ≥ min_z
// (a light at the horizon lights nothing; min_z = cos(cone) keeps them within
// a cone about the view axis). Deterministic for a seed.
Eigen::MatrixX3d random_hemisphere_lights(int count, double min_z, std::uint64_t seed);

struct SyntheticOptions {
  // Values are scale · shading; 0 normalises so that the brightest exact value is 1.
  double scale = 0;
  // λ of the noise, with 16-bit quantisation and values ≥ 1 flagged saturated
  // (λ = 0: quantisation only); < 0: exact values in float.
  double noise = -1;
  std::uint64_t seed = 1;  // of the noise
};

struct SyntheticScene {
  Observations observations;  // every pixel in the mask, distant lights, no near model
  cv::Mat truth;              // CV_32FC3, the normal of each pixel
};

// size.width × size.height pixels whose normal is normal_at(x, y).
using NormalGrid = std::function<Vec3(int x, int y)>;
SyntheticScene render_synthetic(const sim::Material& material, cv::Size size, const NormalGrid& normal_at,
                                const Eigen::MatrixX3d& lights, const SyntheticOptions& options);

// The dissertation's 1620 normals: 36 azimuths (10°..360°) over columns, 45
// elevations (2°..90°) over rows.
cv::Size sweep_grid_size();
Vec3 sweep_grid_normal(int x, int y);

}  // namespace lightstage::pipeline
