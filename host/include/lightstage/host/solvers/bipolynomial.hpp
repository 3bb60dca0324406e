#pragma once
// Bi-polynomial photometric stereo (dissertation Chapter 3, Algorithm 2;
// ALGORITHMS.md §3). Per pixel:
//  1. drop shadows (value ≤ shadow_threshold) and saturated observations,
//     sort the rest and keep the lowest t_low fraction (the low-frequency
//     reflectance; at least terms + 2 observations are kept when available);
//  2. initial normal: Lambertian least squares on the kept observations (or,
//     opt-in, on the lit observations ranked in the start band [LOW, HIGH));
//  3. alternate until the residual |ρ(n, L)∘(nᵀL) − i|² changes by less than
//     `tolerance` or `max_iterations` pass: fix n → solve the coefficients C
//     by linear least squares; fix ρ_j → solve n from i_j = ρ_j (l_jᵀn) by
//     linear least squares and normalise it. The best iterate is kept.
// Outputs beyond the normal: the coefficients C (reflectance/bipolynomial_model.hpp),
// albedo = mean of ρ over the kept observations (the Lambertian albedo for a
// Lambertian surface), the RMS residual, and confidence = 1 − RMS / mean kept value.

#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/solvers/pixel_observations.hpp"
#include "lightstage/host/solvers/solve_result.hpp"

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <vector>

namespace lightstage {

struct BiPolynomialOptions {
  int order = 2;                   // 1 bilinear, 2 biquadratic, 3 bicubic
  double t_low = 0.25;             // kept fraction of the lit observations, in (0, 1]
  double shadow_threshold = 1e-6;  // observations ≤ this are shadows (≥ 0)
  // Opt-in start band (0, 0 = off): the initial Lambertian fit uses the lit
  // observations ranked in [low, high) (fractions; widened downwards to
  // terms + 2 observations when narrower) instead of the T_low set,
  // skipping the darkest as well as the specular ones. Why: with lights in a
  // narrow cone the alternation barely moves the initial zenith (a radial
  // tilt and a fall-off of ρ at grazing incidence explain the data alike), so
  // a start biased by grazing observations stays biased. On the DiLiGenT ball
  // (43° cone; reflectance 0.87–0.94 of Lambert's at 60–80° incidence)
  // 0.2,0.5 takes biquadratic from 2.21° to 1.49° and auto from 2.16° to
  // 1.57°. Not the default: on the material sweep with lights in a 43° cone
  // (`bench materials --light-cone 43`), whose materials have no such
  // fall-off, it costs biquadratic 1.55° -> 2.99° without noise (Oren–Nayar,
  // specular tails in the band), and over the hemisphere 0.56° -> 1.31°.
  double start_band_low = 0;
  double start_band_high = 0;
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
  std::vector<Eigen::Index> candidates, kept, initial;
  Eigen::MatrixXd design;
  Eigen::VectorXd target, rho, basis;
  Eigen::MatrixX3d halves;
};

// The per-pixel core (any light matrix: distant or per-pixel near lights).
BiPolynomialPixelFit fit_bipolynomial_pixel(const PixelObservations& pixel,
                                            const BiPolynomialOptions& options,
                                            BiPolynomialWorkspace& workspace);

// Every pixel; method name "bilinear" / "biquadratic" / "bicubic".
SolveResult solve_bipolynomial(const Observations& observations, const BiPolynomialOptions& options = {});

}  // namespace lightstage
