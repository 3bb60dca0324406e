#pragma once
// Robust Lambertian photometric stereo: the Lambertian model fitted only to
// the observations it can explain. Per pixel:
//  1. selection: drop shadows (value ≤ shadow_threshold) and saturated
//     observations;
//  2. cast-shadow screen (screen_cast_shadows, default off): a locally
//     optimised RANSAC consensus over every lit observation; when at least
//     half of them agree with it, the values under half its prediction and
//     the lights it puts at its terminator are dropped (cast shadows,
//     penumbrae and dark noise: the values step 3 would otherwise prefer);
//  3. keep the lowest t_low fraction (drops highlights);
//  4. a statistical estimator on what is left:
//     - irls-l1 (default): iteratively reweighted least squares for
//       min Σ|l_j·s − i_j| (weights 1 / max(|r_j|, ε), ε = irls_epsilon ×
//       median value);
//     - ransac: exact solutions from random light triples facing the camera,
//       the one with most observations within ransac_threshold × median
//       value wins (stopping once an all-inlier triple was drawn with
//       probability 0.999), then least squares on its inliers, re-taken from
//       each refit; the random sequence is seeded per pixel, so results do
//       not depend on the thread count;
//     - none: least squares on the selection;
//  5. inlier refit (inlier_sigmas > 0, default 3): the estimator's fit
//     measures the pixel's noise (σ from its residuals; with distant lights
//     growing as the square root of the predicted value, as shot noise does,
//     above a tenth of the selection's median; with near lights, whose surface
//     point is a guess, constant); every lit value within inlier_sigmas σ
//     of the fit — T_low's dropped values too, when the fit explains them
//     about as well as the selection — is refitted by weighted least squares.
// The screen is off by default: with the shadow threshold estimated from the
// data it changes nothing on the cast-shadow bunnies and the DiLiGenT ball,
// and costs accuracy on the material sweep (docs/solvers.md).
// Outputs: normal, albedo |s|, RMS residual over the selection.

#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/solvers/pixel_observations.hpp"
#include "lightstage/host/solvers/solve_result.hpp"

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace lightstage {

enum class RobustEstimator { kNone, kIrlsL1, kRansac };
const char* robust_estimator_name(RobustEstimator estimator);
RobustEstimator parse_robust_estimator(const std::string& text);  // "none" | "irls-l1" | "ransac"

struct RobustOptions {
  double shadow_threshold = 1e-6;  // observations ≤ this are shadows (≥ 0)
  double t_low = 0.5;              // kept fraction of the lit observations, in (0, 1]
  RobustEstimator estimator = RobustEstimator::kIrlsL1;
  // Drop lit values well below a RANSAC consensus fit before the T_low
  // selection (cast shadows; docs/solvers.md "The robust family").
  bool screen_cast_shadows = false;
  // Refit after the estimator: weighted least squares on the observations
  // within this many noise deviations of its fit (0 = off; robust.cpp).
  double inlier_sigmas = 3;
  int irls_iterations = 30;        // irls-l1: reweighting rounds
  double irls_epsilon = 1e-3;      // irls-l1: residual floor, relative to the median value
  int ransac_iterations = 200;     // ransac: triples tried
  double ransac_threshold = 0.05;  // ransac / confidence: inlier band, relative to the median value
  std::uint64_t seed = 1;          // ransac
  int min_observations = 3;        // fewer left after selection: rejected (≥ 3)
  bool drop_saturated = true;
  int threads = 0;
  SolveProgress progress;  // pixels done (solve_result.hpp); not part of to_json()

  void check() const;  // throws InputError naming the field and value
  nlohmann::json to_json() const;
};

struct RobustPixelFit {
  enum class Status { kSolved, kTooFewObservations, kDegenerate };
  Status status = Status::kDegenerate;
  Eigen::Vector3d s = Eigen::Vector3d::Zero();  // albedo × normal
  double rms = 0;
  double inlier_fraction = 0;
};

struct RobustWorkspace {
  std::vector<Eigen::Index> kept, inliers;
  Eigen::VectorXd weights;
  std::vector<double> scratch;
  std::vector<std::uint8_t> in_selection;
};

// The per-pixel core; `pixel_index` seeds RANSAC.
RobustPixelFit fit_robust_pixel(const PixelObservations& pixel, const RobustOptions& options,
                                std::size_t pixel_index, RobustWorkspace& workspace);

SolveResult solve_robust(const Observations& observations, const RobustOptions& options = {});

}  // namespace lightstage
