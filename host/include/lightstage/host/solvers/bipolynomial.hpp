#pragma once
// Bi-polynomial photometric stereo (dissertation Chapter 3, Algorithm 2;
// ALGORITHMS.md §3). Per pixel:
//  1. drop shadows (value ≤ shadow_threshold) and saturated observations,
//     sort the rest and keep the lowest t_low fraction (the low-frequency
//     reflectance; at least terms + 2 observations are kept when available);
//  2. initial normal: least squares on the kept observations of
//     i = a (t + κ t²), t = n·l, with the object's incidence fall-off κ
//     (incidence_falloff.hpp; κ = 0 is the dissertation's Lambertian start);
//  3. alternate until the residual |ρ(n, L)∘(nᵀL) − i|² changes by less than
//     `tolerance` or `max_iterations` pass: fix n → solve the coefficients C
//     by linear least squares; fix ρ_j → solve n from i_j = ρ_j (l_jᵀn) by
//     linear least squares and normalise it. The best iterate is kept.
// Outputs beyond the normal: the coefficients C (reflectance/bipolynomial_model.hpp),
// albedo = mean of ρ over the kept observations (the Lambertian albedo for a
// Lambertian surface) and the RMS residual.

#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/solvers/incidence_falloff.hpp"
#include "lightstage/host/solvers/pixel_observations.hpp"
#include "lightstage/host/solvers/solve_result.hpp"

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <optional>
#include <vector>

namespace lightstage {

struct BiPolynomialOptions {
  int order = 2;                   // 1 bilinear, 2 biquadratic, 3 bicubic
  double t_low = 0.25;             // kept fraction of the lit observations, in (0, 1]
  double shadow_threshold = 1e-6;  // observations ≤ this are shadows (≥ 0)
  // κ of the start (incidence_falloff.hpp). Unset: solve_bipolynomial and
  // solve_auto estimate it from the object; 0: the Lambertian start, as
  // published. fit_bipolynomial_pixel takes an unset value as 0.
  std::optional<double> falloff;
  // The object's κ estimated beforehand (over every band of a stack read in
  // bands: FalloffSamples); with falloff unset, used instead of an estimate
  // from the observations solved. Not part of to_json().
  std::optional<FalloffEstimate> falloff_estimate;
  int max_iterations = 100;    // alternations, ≥ 1
  double tolerance = 1e-7;     // stop when the squared residual changes less
  bool drop_saturated = true;  // drop observations flagged saturated
  int threads = 0;             // 0 = hardware concurrency; results do not depend on it
  SolveProgress progress;      // pixels done (solve_result.hpp); not part of to_json()

  void check() const;  // throws InputError naming the field and value
  nlohmann::json to_json() const;
};

struct BiPolynomialPixelFit {
  enum class Status { kSolved, kTooFewObservations, kDegenerate };
  Status status = Status::kDegenerate;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  Eigen::VectorXd coefficients;  // (order + 1)² terms
  double rms = 0;                // over the kept observations
  double mean_kept = 0;          // mean kept value (confidence scale)
  double albedo = 0;
  int iterations = 0;
  int kept = 0;
};

// Reusable per-thread buffers.
struct BiPolynomialWorkspace {
  std::vector<Eigen::Index> candidates, kept;
  Eigen::MatrixXd design;
  Eigen::VectorXd target, rho, basis;
  Eigen::MatrixX3d halves;
};

// Step 1 for one pixel: workspace.candidates = the lit, usable observations
// sorted by value, workspace.kept = their lowest t_low fraction (at least
// terms + 2). False when fewer than terms + 2 are lit.
bool select_low_frequency(const PixelObservations& pixel, const BiPolynomialOptions& options,
                          BiPolynomialWorkspace& workspace);

// The per-pixel core (any light matrix: distant or per-pixel near lights).
BiPolynomialPixelFit fit_bipolynomial_pixel(const PixelObservations& pixel,
                                            const BiPolynomialOptions& options,
                                            BiPolynomialWorkspace& workspace);

// Sets options.falloff, when it is unset, from options.falloff_estimate or
// else from the observations, and returns that estimate (nothing when
// options.falloff was given).
std::optional<FalloffEstimate> resolve_falloff(const Observations& observations,
                                               BiPolynomialOptions& options);

// {"kappa", "estimated", and the estimate's quartiles and pixel count} for
// a result's parameters.
nlohmann::json falloff_json(const BiPolynomialOptions& options,
                            const std::optional<FalloffEstimate>& estimate);

// The summary's "mean_iterations" finding.
SolveFact mean_iterations_fact(double mean);

// Every pixel; method name "bilinear" / "biquadratic" / "bicubic".
SolveResult solve_bipolynomial(const Observations& observations, const BiPolynomialOptions& options = {});

}  // namespace lightstage
