#pragma once
// The per-pixel reflectance that relighting uses, fitted once the normals are
// known. A bi-polynomial solve finds its normal from the darkest T_low part of
// each pixel's lit values, so its coefficients describe that part only and
// extrapolate wildly towards the highlights and grazing lights they never saw.
// Here, at the solved normal, the coefficients are refitted to every lit,
// unsaturated observation, held towards the object's own BRDF:
//   ρ_p(x, y) = Σ c_p,t x^i y^j,    x = n·h, y = l·h   (bipolynomial_model.hpp)
//   c_p = argmin Σ_j ((n·l_j) b(x_j, y_j)ᵀ c − v_j)² + λ Σ_t D_t (c_t − s_p g_t)²
// g: the object BRDF, one least-squares fit over the pixels of their values
// divided by each pixel's Lambertian albedo; s_p: the pixel's scale of it;
// D_t: the mean over pixels of Σ_j ((n·l_j) b_t)², so that λ = 1 weighs the
// prior as much as an average pixel's data. Where a pixel's lights leave terms
// undetermined (few lit lights, a narrow range of x or y) the prior fills
// them in, instead of the noise. λ is chosen by cross-validation over the
// lights (every folds-th light held out in turn, on a sample of pixels),
// scoring the relit value max(ρ, 0)·(n·l) as `relight` renders it.

#include "lightstage/host/radiometry.hpp"

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <optional>
#include <vector>

namespace lightstage {

struct RelightingFitOptions {
  int order = 2;                 // bi-polynomial order of the coefficients written
  double shadow_threshold = 0;   // values at or below it are not lit (the solve's threshold)
  std::optional<double> lambda;  // fixed prior weight; empty = chosen by cross-validation
  std::vector<double> lambdas;   // the candidates (empty = a default grid from 0 to 1000)
  int folds = 8;                 // cross-validation folds over the lights
  int sample_pixels = 4000;      // pixels the cross-validation uses (evenly spread)
  int threads = 0;               // 0 = hardware concurrency

  void check() const;  // throws InputError naming the field and value
};

struct RelightingFit {
  cv::Mat coefficients;         // CV_32FC(k): per-pixel coefficients where solved, else 0
  Eigen::VectorXd object_brdf;  // g
  double lambda = 0;            // the weight used
  // Cross-validated relative RMSE of the relit held-out values per candidate λ
  // (empty when λ was fixed).
  std::vector<std::pair<double, double>> validation;
  std::size_t pixels = 0;  // pixels refitted

  nlohmann::json to_json() const;  // for the solve's reflectance description
};

// Refits the coefficients of every solved pixel of `normals` (CV_32FC3) /
// `solved` (CV_8UC1) from `observations`. Pixels with no lit observation get
// the prior alone scaled by their Lambertian value. Throws InputError when
// the maps do not match the observations.
RelightingFit fit_relighting_brdf(const Observations& observations, const cv::Mat& normals,
                                  const cv::Mat& solved, const RelightingFitOptions& options);

}  // namespace lightstage
