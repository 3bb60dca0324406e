#pragma once
// `auto`: the dissertation's open problem (§5.3.1) — per pixel, choose
// between (or blend) the bi-polynomial and the monotonicity answers from
// evidence in the data. The two methods have different favourite materials:
// monotonicity wants one sharp lobe around h, the bi-polynomial model wants
// broad low-frequency reflectance. Per pixel:
//  1. bi-polynomial answer: bilinear and biquadratic fits on the same T_low
//     set; the one with the lower BIC, m·ln(RSS/m) + terms·ln(m), wins (noise
//     makes the extra biquadratic terms fit noise, and BIC sees it);
//  2. monotonic answer: elevation search of δ with the plateau descent (and
//     the 2-D refinement when enabled) at the bi-polynomial normal's azimuth;
//  3. evidence: the two answers' angle d, and how one-lobe the profile
//     i/(n·l) against n·h is at each (profile_monotonicity s_m, s_b).
//     When they agree (d ≤ agreement_deg) the errors are largely independent
//     and the normal is their mean; when they disagree the monotonic answer
//     is taken only if its profile is clearly more monotonic
//     (s_m − s_b ≥ monotonic_margin), otherwise the bi-polynomial one. The
//     default margin 1 never switches: measured on the material sweep and
//     the DiLiGenT ball, s_m − s_b favours the monotonic answer by
//     construction (it maximises monotonicity), including where it is wrong
//     (lights in a cone, Oren–Nayar, noise).
// The BRDF written is the biquadratic layout (a bilinear winner's
// coefficients fill its C_00, C_01, C_10, C_11); SolveResult::choice says
// which answer each pixel took.

#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/solvers/bipolynomial.hpp"
#include "lightstage/host/solvers/monotonic.hpp"
#include "lightstage/host/solvers/solve_result.hpp"

#include <nlohmann/json.hpp>

namespace lightstage {

struct AutoOptions {
  BiPolynomialOptions bipolynomial;  // the bi-polynomial candidate (biquadratic by default)
  MonotonicOptions monotonic;        // the monotonic candidate
  double agreement_deg = 2.0;        // answers closer than this are averaged, (0, 90]
  double monotonic_margin = 1.0;     // s_m − s_b needed to prefer the monotonic answer, [0, 1]
  bool select_order = true;          // BIC choice between bilinear and biquadratic (else biquadratic)
  int threads = 0;                   // overrides both candidates' threads
  SolveProgress progress;            // pixels done (solve_result.hpp; the candidates' own are not used)

  void check() const;  // throws InputError naming the field and value
  nlohmann::json to_json() const;
};

SolveResult solve_auto(const Observations& observations, const AutoOptions& options = {});

// The summary's "method_counts" finding: `counts` ({choice name: pixels})
// and their shares of the `solved` pixels.
SolveFact method_counts_fact(const nlohmann::json& counts, std::size_t solved);

}  // namespace lightstage
