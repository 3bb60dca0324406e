#pragma once
// Robust Lambertian photometric stereo: the Lambertian model fitted only to
// the observations it can explain. Per pixel:
//  1. selection: drop shadows (value ≤ shadow_threshold) and saturated
//     observations, then keep the lowest t_low fraction (default 1: all;
//     lower values drop highlights but also keep penumbrae, so they lose on
//     cast shadows);
//  2. a statistical estimator on what is left:
//     - ransac (default): exact solutions from random light triples facing
//       the camera, the one with most observations within ransac_threshold ×
//       median value wins, then least squares on its inliers, whose set is
//       re-taken from each refit (locally optimised RANSAC); the random
//       sequence is seeded per pixel, so results do not depend on the thread
//       count. It beats the published robust family (rpca, l1, sbl) on the
//       cast-shadow and specular bunnies (tests/pipeline/robust_family_test);
//     - irls-l1: iteratively reweighted least squares for min Σ|l_j·s − i_j|
//       (weights 1 / max(|r_j|, ε), ε = irls_epsilon × median value);
//     - none: least squares on the selection.
// Outputs: normal, albedo |s|, RMS residual over the selection, confidence =
// the fraction of the selection the final fit explains within the inlier band.

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
  bool screen_cast_shadows = true;
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
};

// The per-pixel core; `pixel_index` seeds RANSAC.
RobustPixelFit fit_robust_pixel(const PixelObservations& pixel, const RobustOptions& options,
                                std::size_t pixel_index, RobustWorkspace& workspace);

SolveResult solve_robust(const Observations& observations, const RobustOptions& options = {});

}  // namespace lightstage
