#pragma once
// Binds library Options structs to CLI flags, once, for every command that
// takes them.

#include "lightstage/host/progress.hpp"
#include "lightstage/pipeline/solve_folder.hpp"
#include "lightstage/pipeline/solve_settings.hpp"
#include "lightstage/sim/simulate.hpp"

#include <CLI/CLI.hpp>

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

// Flags of `solve` (and `demo`): every method's options (pipeline/solve_settings.hpp).
void add_solve_flags(CLI::App& sub, pipeline::SolveSettings& settings);
// What `solve` and `batch` are told: where to read and write, every method's
// settings and the lights' calibration.
struct SolveCommandArgs {
  std::string input;
  std::string out;
  OutputFlags output;
  pipeline::SolveSettings solve;
  pipeline::SolveCalibration calibration;
};
// --calibration, --distant-lights and --response of `solve` and `batch`.
void add_solve_calibration_flags(CLI::App& sub, pipeline::SolveCalibration& calibration);

}  // namespace lightstage::cli
