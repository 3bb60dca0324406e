#pragma once
// Robust photometric stereo by sparse regression (Ikehata, Wipf, Matsushita,
// Aizawa, CVPR 2012; ALGORITHMS.md "Robust family"). Per pixel the observations
// are i = L s + e with e sparse (specular highlights, cast shadows the
// threshold missed); shadowed observations (value ≤ shadow_threshold) and
// saturated ones are removed before the regression, as the paper does.
//  - l1:  s = argmin ‖i − L s‖₁, by iteratively reweighted least squares
//         (weights 1 / max(|r_j|, ε), ε = epsilon × median value).
//  - sbl: sparse Bayesian learning: e_j ~ N(0, γ_j), noise N(0, λ), s with a
//         flat prior; γ is learned by EM on the marginal likelihood (the
//         hyper-parameters of the errors the model needs go to zero).
// Outputs: normal, albedo |s|, RMS residual over the kept observations.

#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/solvers/solve_result.hpp"

#include <nlohmann/json.hpp>

namespace lightstage {

struct L1Options {
  double shadow_threshold = 1e-6;  // observations ≤ this are shadows (≥ 0)
  int iterations = 50;             // reweighting rounds
  double epsilon = 1e-4;           // residual floor, relative to the median kept value
  int min_observations = 3;        // fewer left: rejected (≥ 3)
  bool drop_saturated = true;
  int threads = 0;         // 0 = hardware concurrency; results do not depend on it
  SolveProgress progress;  // not part of to_json()

  void check() const;  // throws InputError naming the field and value
  nlohmann::json to_json() const;
};

struct SblOptions {
  double shadow_threshold = 1e-6;  // observations ≤ this are shadows (≥ 0)
  int iterations = 100;            // EM rounds
  double noise = 1e-2;             // √λ, relative to the median kept value
  int min_observations = 3;
  bool drop_saturated = true;
  int threads = 0;
  SolveProgress progress;

  void check() const;
  nlohmann::json to_json() const;
};

SolveResult solve_l1(const Observations& observations, const L1Options& options = {});
SolveResult solve_sbl(const Observations& observations, const SblOptions& options = {});

// The setting l1 and sbl report: their mean reweighting or EM rounds per solved pixel.
SolveFact iterations_per_pixel_fact(double mean);

}  // namespace lightstage
