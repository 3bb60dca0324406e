#pragma once
// Reflectometry with known normals (dissertation §3.5): one BRDF for a whole
// object, fitted to every (normal, light, value) sample the stack holds.
// Models: Lambert (ρ = a), the bi-polynomial models (linear least squares on
// ρ(x, y) · (n·l), reflectance/bipolynomial_model.hpp) and Cook–Torrance
// (ρ = kd + ks · π·D F G / (4 (n·l)(n·v)), Beckmann D with roughness m,
// Schlick F with f0; m and f0 on a grid, kd and ks ≥ 0 by least squares).
// Errors are reported on the samples the model was fitted to.

#include "lightstage/common/geometry.hpp"
#include "lightstage/host/radiometry.hpp"

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace lightstage {

struct ReflectanceSamples {
  std::vector<Vec3> normals, lights;
  std::vector<double> values;  // at unit light (near-light gains divided out)
  std::size_t size() const { return values.size(); }
};

struct SampleOptions {
  double shadow_threshold = 1e-6;  // drop values ≤ this
  double t_low = 1.0;              // per pixel, keep the lowest fraction (1 = every lit observation)
  bool drop_saturated = true;
  std::size_t max_samples = 2000000;  // evenly thinned beyond this

  void check() const;  // throws InputError naming the field
};

// Samples at every pixel where `normals` (CV_32FC3) holds a normal.
ReflectanceSamples collect_samples(const Observations& observations, const cv::Mat& normals,
                                   const SampleOptions& options = {});

struct ReflectanceFit {
  std::string model;  // "lambert", "bilinear", "biquadratic", "bicubic", "cook-torrance"
  Eigen::VectorXd
      parameters;   // lambert: [a]; bi-polynomial: C (storage order); cook-torrance: [kd, ks, m, f0]
  double rmse = 0;  // of ρ·(n·l) against the values
  double mae = 0;
  double relative_rmse = 0;  // rmse / mean value
  nlohmann::json to_json() const;
};

ReflectanceFit fit_lambert(const ReflectanceSamples& samples);
ReflectanceFit fit_bipolynomial_model(const ReflectanceSamples& samples, int order);
ReflectanceFit fit_cook_torrance(const ReflectanceSamples& samples);

// π·D F G / (4 (n·l)(n·v)) of the Cook–Torrance specular lobe (0 below the horizon).
double cook_torrance_lobe(const Vec3& n, const Vec3& l, const Vec3& v, double roughness, double f0);

}  // namespace lightstage
