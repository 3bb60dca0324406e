#pragma once
// Binds library Options structs to CLI flags, once, for every command that
// takes them.

#include "lightstage/host/progress.hpp"
#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/solvers/auto.hpp"
#include "lightstage/host/solvers/bipolynomial.hpp"
#include "lightstage/host/solvers/lambertian.hpp"
#include "lightstage/host/solvers/monotonic.hpp"
#include "lightstage/host/solvers/robust.hpp"
#include "lightstage/sim/simulate.hpp"
#include "shape_prior_args.hpp"

#include <CLI/CLI.hpp>

#include <memory>
#include <optional>
#include <string>

namespace lightstage::cli {

// --quiet and --json of the long commands (simulate, solve, integrate, bench):
// on a terminal a progress line with an estimate of the time left (stderr);
// --quiet prints nothing but errors; --json prints exactly one JSON object on
// stdout and nothing else there.
struct OutputFlags {
  bool quiet = false;
  bool json = false;
  OutputMode mode() const {
    return json ? OutputMode::kJson : quiet ? OutputMode::kQuiet : OutputMode::kHuman;
  }
  bool human() const { return !quiet && !json; }
};
// Adds --quiet and --json; `json_what` says what the object holds.
void add_output_flags(CLI::App& sub, OutputFlags& flags, const std::string& json_what);
// Call first in the callback: --quiet lowers logging to errors, --json to
// warnings (both on stderr), unless --log-level was given.
void apply_output_flags(const CLI::App& sub, const OutputFlags& flags);

// Flags of `simulate` (and `demo`): scene, material, lights, sensor.
struct SimulateArgs {
  sim::SimulateOptions options;
  std::string light_model = "near";
  std::string noise = "physical";
  std::string response = "identity";
  bool no_cast_shadows = false;
  // Fills options from the string flags; call in the callback.
  void resolve();
};
void add_simulate_flags(CLI::App& sub, SimulateArgs& args);

// Flags of `solve` (and `demo`): the Lambertian solver and radiometry.
struct SolveArgs {
  std::string method = "l2";
  L2Options l2;
  RobustOptions robust;
  MonotonicOptions monotonic;
  BiPolynomialOptions bipolynomial;
  AutoOptions automatic;
  ShapePriorArgs shape_prior;         // --method shape-prior (shape_prior_args.hpp)
  std::string estimator = "irls-l1";  // --estimator, robust
  std::string azimuth_from =
      "robust";  // --azimuth-from, monotonic (robust: better on the sweep and the ball)
  // Flags every method shares: when given, resolve() copies them into each method's options.
  std::optional<double> shadow_threshold, t_low;
  std::optional<int> min_observations, threads, max_iterations;
  std::string falloff = "auto";  // --falloff auto|K: bi-polynomial and auto (incidence_falloff.hpp)
  RadiometryOptions radiometry;
  bool no_clamp = false;
  void resolve();
  // Gives every method's options the same progress report (solve_result.hpp).
  void set_progress(const SolveProgress& progress);
};
void add_solve_flags(CLI::App& sub, SolveArgs& args);

// --falloff: "auto" (estimated from the object) or a number in [kMinFalloff,
// kMaxFalloff]; throws InputError naming the flag.
std::optional<double> parse_falloff(const std::string& text);

}  // namespace lightstage::cli
