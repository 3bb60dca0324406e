#pragma once
// The steps that commands share (demo = simulate + solve + eval), each one
// library call plus its files, so that every command stays a thin wrapper.

#include "lightstage/common/rig.hpp"
#include "lightstage/host/eval/angular_error.hpp"
#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/solvers/lambertian.hpp"
#include "lightstage/sim/simulate.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <optional>

namespace lightstage::cli {

// Simulates `rig` under `options` and writes the stack (with ground truth and
// manifest) into `out`. Returns a JSON summary of what was written.
// `on_frames` (optional) hears of every frame rendered (sim::simulate_stack).
nlohmann::json simulate_to_folder(const std::filesystem::path& rig_path, const sim::SimulateOptions& options,
                                  const std::filesystem::path& out, const sim::FrameProgress& on_frames = {});

struct SolveReport {
  nlohmann::json summary;                  // as written to summary.json
  std::optional<AngularErrorStats> error;  // when the stack holds ground truth
};

// Loads the stack in `input`, solves it with Lambertian least squares and
// writes the results into `out`. When the stack holds ground truth, the
// angular error is measured and recorded in summary.json too.
SolveReport solve_folder(const std::filesystem::path& input, const RadiometryOptions& radiometry,
                         const L2Options& options, const std::filesystem::path& out);

// A light calibration to apply before solving (docs/calibration.md): its
// directions and intensities replace the stack's; its LED positions give
// near lights unless `distant` is set.
struct SolveCalibration {
  std::filesystem::path file;  // calibration.json or .lp; empty = none
  bool distant = false;
};

// The same with any solver (e.g. a method of the --method table, methods.hpp).
using SolverFunction = std::function<SolveResult(const Observations&)>;
SolveReport solve_folder(const std::filesystem::path& input, const RadiometryOptions& radiometry,
                         const SolverFunction& solver, const std::filesystem::path& out,
                         const SolveCalibration& calibration = {});

// Writes RESULT_DIR/report.html (report/report.hpp) for a solve of the stack
// in `input`; a failure is logged as a warning, not thrown.
void write_result_report(const std::filesystem::path& result_dir, const std::filesystem::path& input);

// Prints a one-line human summary of angular error statistics.
void print_error_stats(const AngularErrorStats& stats);

}  // namespace lightstage::cli
