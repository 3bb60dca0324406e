#pragma once
// Binds library Options structs to CLI flags, once, for every command that
// takes them.

#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/solvers/lambertian.hpp"
#include "lightstage/sim/simulate.hpp"

#include <CLI/CLI.hpp>

#include <memory>
#include <string>

namespace lightstage::cli {

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
  RadiometryOptions radiometry;
  bool no_clamp = false;
  void resolve() { radiometry.clamp_to_one = !no_clamp; }
};
void add_solve_flags(CLI::App& sub, SolveArgs& args);

}  // namespace lightstage::cli
