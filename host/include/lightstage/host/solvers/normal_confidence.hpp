#pragma once
// A confidence for every method's normals that predicts its error, from the
// pixel's own observations around the method's answer (n, ρ). The lit lights
// facing n whose Lambertian residual r_j = v_j − ρ lᵀ_j n is within
// `trim` × their median |r| are the inliers (shadows and highlights drop
// out, as any robust method drops them; with three lit lights, all three).
// Two parts, in degrees:
// - spread: the normal's standard error from the sandwich covariance of a
//   Lambertian fit to the inliers, C = M⁻¹ (Σ r_j² l_j lᵀ_j) M⁻¹ with
//   M = Σ l_j lᵀ_j and r_j the answer's own residuals (floored at
//   `min_relative_sigma` of the mean lit value): e_s = √tr(P C P) / ρ,
//   P = I − n nᵀ. Unlike σ² M⁻¹ it weighs each light's residual where it
//   has leverage, so residuals the answer leaves at grazing or one-sided
//   light count more;
// - disagreement: the angle between n and the inliers' least-squares
//   normal M⁻¹ Σ v_j l_j, where the method's answer is pulled away from
//   what its clean observations say (outliers it kept, a model that bends).
// e = √(e_s² + e_d²); confidence = 1 / (1 + e / s), s =
// ConfidenceOptions::scale_deg, so e = s (1/c − 1) reads it back.

#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/solvers/confidence_options.hpp"
#include "lightstage/host/solvers/solve_result.hpp"

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

namespace lightstage {

// The unit normal the confidence judges for a solved pixel: the stored one,
// or none (false) when it is not a normal.
bool judged_normal(const cv::Vec3f& stored, Eigen::Vector3d& n);

// Predicted angular error in degrees (CV_32FC1, the result's size) for every
// solved pixel of `result`; +inf where fewer than three inliers remain or
// they are coplanar; 0 where not solved.
cv::Mat predict_normal_error(const Observations& observations, const SolveResult& result,
                             const ConfidenceOptions& options);

// Confidence in [0, 1] from predicted errors: 1 / (1 + e / scale_deg); 0 where
// `solved` is zero.
cv::Mat confidence_from_error(const cv::Mat& error_deg, const cv::Mat& solved, double scale_deg);

}  // namespace lightstage
