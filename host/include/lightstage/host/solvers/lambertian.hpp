#pragma once
// Lambertian least squares (Woodham; ALGORITHMS.md §1): per pixel
// s = argmin |L s − i|², n = s / |s|, albedo = |s|.
// With every observation used (no shadow threshold, t_low = 1) all pixels
// share one pseudo-inverse of L — the DiLiGenT baseline, exactly. Otherwise
// each pixel selects its observations and solves its own 3×3 normal equations.
// Pixels with fewer than min_observations observations left, or whose lights
// are (nearly) coplanar, or whose solution is zero, are rejected, not guessed.

#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/solvers/confidence_options.hpp"
#include "lightstage/host/solvers/solve_result.hpp"

#include <nlohmann/json.hpp>

#include <optional>

namespace lightstage {

struct L2Options {
  // Shadow threshold i0: when ≥ 0, observations ≤ i0 are dropped. −1 = keep all.
  double shadow_threshold = -1;
  // Keep the lowest fraction of each pixel's remaining observations (ceil of
  // fraction × count), in (0, 1]; 1 = all. "Lambert (low)" in ALGORITHMS.md.
  double t_low = 1.0;
  // A pixel with fewer observations than this (after selection) is rejected; ≥ 3.
  int min_observations = 3;
  // Worker threads over pixels; 0 = hardware concurrency. Results do not depend on it.
  int threads = 0;
  SolveProgress progress;  // pixels done (solve_result.hpp); not part of to_json()
  // When set, each pixel solved one at a time (near lights, a threshold or
  // t_low < 1) also gets the confidence's predicted error at its answer, in
  // SolveResult::predicted_error (empty when every pixel shares one
  // pseudo-inverse); its time counts in the summary's seconds. Not part of
  // to_json() (solve_with records it).
  std::optional<ConfidenceOptions> confidence;

  // Throws InputError naming the broken field and value.
  void check() const;
  nlohmann::json to_json() const;
};

// Solves every pixel of `observations`. Throws InputError for bad options.
SolveResult solve_lambertian(const Observations& observations, const L2Options& options = {});

}  // namespace lightstage
