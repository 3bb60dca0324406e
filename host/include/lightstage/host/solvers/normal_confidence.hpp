#pragma once
// A confidence for every method's normals that predicts its error: the
// spread the photometric data leave the normal, from the local curvature of
// a Lambertian cost around the method's answer. With b = ρ n fitted to the
// lit observations v_j ≈ lᵀ_j b, the covariance of b is σ² M⁻¹ with
// M = Σ l_j lᵀ_j over the lit lights, so the normal's angular spread is
//   e = σ / ρ · √tr(P M⁻¹ P),   P = I − n nᵀ   (radians),
// large where few lights are lit, where they bunch on one side (grazing,
// near the occluding contour), where the albedo is dark, and where the data
// depart from the model (σ: the method's own RMS residual, or the Lambertian
// one where the method has none in value units). Confidence = 1 / (1 + e / s),
// s = ConfidenceOptions::scale_deg, so e = s (1/c − 1) reads it back.

#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/solvers/solve_result.hpp"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

namespace lightstage {

struct ConfidenceOptions {
  double shadow_threshold = 0;       // observations at or below it are not lit (the solve's threshold)
  double scale_deg = 1.0;            // s: the predicted error at which confidence is 0.5
  bool method_residual = true;       // σ from SolveResult::residual (else the Lambertian residual)
  double min_relative_sigma = 1e-3;  // σ floor, relative to the pixel's mean lit value (quantisation)
  int threads = 0;                   // 0 = hardware concurrency

  void check() const;  // throws InputError naming the field and value
  nlohmann::json to_json() const;
};

// Predicted angular error in degrees (CV_32FC1, the result's size) for every
// solved pixel of `result`; +inf where fewer than three lit lights remain or
// they are coplanar; 0 where not solved.
cv::Mat predict_normal_error(const Observations& observations, const SolveResult& result,
                             const ConfidenceOptions& options);

// Confidence in [0, 1] from predicted errors: 1 / (1 + e / scale_deg); 0 where
// `solved` is zero.
cv::Mat confidence_from_error(const cv::Mat& error_deg, const cv::Mat& solved, double scale_deg);

}  // namespace lightstage
