#pragma once
// The photometric-stereo methods by name: a registry from a name to a solve
// function over the observations and the settings (solve_settings.hpp), with
// one help line each. `solve --method`, the demo, the material sweep and the
// Python module all look methods up here, so a new method is one entry (and
// its options in SolveSettings) and no caller changes.

#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/reflectance/relighting_fit.hpp"
#include "lightstage/host/shadow_threshold.hpp"
#include "lightstage/host/solvers/solve_result.hpp"
#include "lightstage/pipeline/solve_settings.hpp"

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace lightstage::pipeline {

using SolveFunction =
    std::function<SolveResult(const Observations& observations, const SolveSettings& settings)>;

struct SolveMethod {
  std::string name;
  std::string help;  // one line, for --help
  SolveFunction solve;
};

// Every method, in the order --help lists them: the built-in ones, then any registered.
const std::vector<SolveMethod>& solve_methods();
std::vector<std::string> solve_method_names();
// Throws InputError naming --method and the known names.
const SolveMethod& find_solve_method(const std::string& name);
// Adds a method (at start-up, before any solve: the registry is not locked).
// Throws InputError when the name is taken or empty.
void register_solve_method(SolveMethod method);

// Solves with settings.method (settings resolved: SolveSettings::resolve),
// with the checks of solve_checks.hpp around it: throws InputError for lights
// of rank < 3, logs (and records under parameters.warnings) a method used
// outside its assumptions, clamps normals facing away (facts
// normals_facing_away). Without --shadow-threshold every method but l2 uses
// `data_threshold`, estimated from the data; the threshold used is recorded
// under parameters.shadow_threshold_choice.
SolveResult solve_with(const Observations& observations, const SolveSettings& settings,
                       const ShadowThreshold& data_threshold);
// The same with the threshold estimated from the observations alone.
SolveResult solve_with(const Observations& observations, const SolveSettings& settings);

// solve_with in two steps, for a stack solved band by band (solve_bands.hpp):
// plan_solve makes the checks and warnings that depend on the lights alone,
// once, and picks the threshold; solve_planned solves one set of
// observations with it. `refit_relighting` false leaves a bi-polynomial
// result's coefficients as the solver gave them (the refit chooses its prior
// over the whole object: refits_relighting).
struct SolvePlan {
  SolveSettings settings;             // with the data threshold given to every method but l2
  ShadowThreshold threshold;          // the threshold used (l2 dropping no shadows: the one recorded)
  std::vector<std::string> warnings;  // logged by plan_solve
};
SolvePlan plan_solve(const Observations& observations, const SolveSettings& settings,
                     const ShadowThreshold& data_threshold);
SolveResult solve_planned(const Observations& observations, const SolvePlan& plan,
                          bool refit_relighting = true);
// parameters.shadow_threshold_choice: the threshold and whether l2 used it.
nlohmann::json shadow_threshold_choice(const ShadowThreshold& threshold, const SolveSettings& settings);
// Whether solve_planned refits `result`'s coefficients for relighting.
bool refits_relighting(const SolveResult& result);
// What that refit is given (the result's order, the plan's threshold and threads).
RelightingFitOptions relighting_fit_options(const SolveResult& result, const SolvePlan& plan);
// The refit said in the result's reflectance: "fit", and the lobe's "specular" and term "S".
void describe_relighting_fit(const RelightingFit& fit, nlohmann::json& reflectance);
// Whether --method's result is refitted for relighting (the bi-polynomial methods and auto), and the
// coefficients a pixel of it may have at most (its polynomial's and the lobe's; 0 for the others).
bool method_refits_relighting(const std::string& method);
int coefficient_terms(const std::string& method);
// What --method's solver holds at once beside a band's observations and maps, whatever the band's
// height, for a stack of `images` (rpca's blocks; 0 for the per-pixel methods).
std::size_t solver_working_bytes(const SolveSettings& settings, std::size_t images);

// The bi-polynomial options with which the method of `settings` estimates the
// object's incidence fall-off κ from the observations it solves
// (bilinear/biquadratic/bicubic, auto, monotonic with its azimuth from one of
// them; solvers/incidence_falloff.hpp), nothing when it does not or --falloff
// gives κ. A stack solved in bands estimates it once from every band, then
// gives every band that estimate (use_falloff_estimate), as a whole-image
// solve would have it.
std::optional<BiPolynomialOptions> falloff_estimating_options(const SolveSettings& settings);
void use_falloff_estimate(SolveSettings& settings, const FalloffEstimate& estimate);
// The normals_facing_away finding for `count` clamped normals.
SolveFact facing_away_fact(std::size_t count);

// What a solve's progress counts: pixels for the per-pixel methods (twice
// over for monotonic with another method's azimuth, which solves every pixel
// first), cost evaluations for shape-prior's refinement.
struct SolveWork {
  std::string unit = "px";
  std::size_t total = 0;
};
SolveWork solve_work(const SolveSettings& settings, const Observations& observations);
SolveWork solve_work(const SolveSettings& settings, std::size_t pixels);

}  // namespace lightstage::pipeline
