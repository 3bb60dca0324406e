#pragma once
// Solving a stack folder into a solve folder: load the stack, apply a light
// calibration, build the observations, run a solver, measure the error when the
// stack holds ground truth, write the outputs (io/solve_output.hpp) and the report.

#include "lightstage/common/image_stack.hpp"
#include "lightstage/host/calibration/apply_calibration.hpp"
#include "lightstage/host/eval/angular_error.hpp"
#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/shadow_threshold.hpp"
#include "lightstage/host/solvers/solve_result.hpp"
#include "lightstage/pipeline/solve_settings.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace lightstage::pipeline {

struct SolveReport {
  nlohmann::json summary;                  // as written to summary.json
  std::optional<AngularErrorStats> error;  // when the stack holds ground truth
};

// A light calibration to apply before solving (docs/calibration.md): its
// directions and intensities replace the stack's; its LED positions give
// near lights unless `distant` is set.
struct SolveCalibration {
  std::filesystem::path file;      // calibration.json or .lp; empty = none
  bool distant = false;            // ignore LED positions (calibration's or the stack's)
  std::filesystem::path response;  // camera response (`camera response`); empty = what the manifest records
};

// A stack folder made ready to solve: its observations (with the calibration
// applied and, when it holds LED positions, near lights), the shadow threshold
// estimated from the stack (shadow_threshold.hpp), the ground truth and what
// the calibration changed.
struct SolveInput {
  Observations observations;
  ShadowThreshold shadow;
  std::optional<GroundTruth> ground_truth;
  nlohmann::json calibration = nullptr;  // describe() of the applied calibration, with near_lights
  nlohmann::json response = nullptr;     // the camera response applied (stack_response.hpp)
  nlohmann::json light_model = nullptr;  // {"model": "near"|"distant", "source": why}
  std::vector<std::string> frame_files;  // the frames' images, one per observation column
};
// `region` (non-empty): only that part of the images is read (--crop), the
// observations placed in the whole image (Observations::origin).
SolveInput load_solve_input(const std::filesystem::path& input, const RadiometryOptions& radiometry,
                            const SolveCalibration& calibration = {}, const cv::Rect& region = {});

// Sets near lights on `observations` (made from `stack`, loaded from
// `input`, with `applied` calibrated) when the calibration or the stack holds
// LED positions and `calibration` does not say distant; returns the choice as
// summary.json records it: {"model": "near"|"distant", "source": why}. With
// `warn`, says when the stack's positions cannot be used.
nlohmann::json set_light_model(const std::filesystem::path& input, const ImageStack& stack,
                               const std::optional<calibration::StackCalibration>& applied,
                               const SolveCalibration& calibration, Observations& observations, bool warn);

using SolverFunction = std::function<SolveResult(const SolveInput&)>;

// Loads the stack in `input`, solves it with `solver` and writes the results
// and report.html into `out`. Throws InputError when `out` is the input
// folder or inside it (io/output_folder.hpp) and, naming the cause, when no
// pixel was solved (SolveSummary::unusable_reason), before writing anything;
// Error when the report fails.
SolveReport solve_folder(const std::filesystem::path& input, const RadiometryOptions& radiometry,
                         const SolverFunction& solver, const std::filesystem::path& out,
                         const SolveCalibration& calibration = {}, const cv::Rect& region = {});

// Starts a progress report of `work` (solve_methods.hpp) and returns what advances it.
struct SolveWork;
using ProgressStart = std::function<SolveProgress(const SolveWork& work)>;

// The same with a method of the registry (settings resolved: SolveSettings::resolve).
// A stack whose solve would need more than settings.memory_limit is solved
// band by band (solve_bands.hpp). `progress`, when set, is started once the
// work is known.
SolveReport solve_folder(const std::filesystem::path& input, const SolveSettings& settings,
                         const std::filesystem::path& out, const SolveCalibration& calibration = {},
                         const ProgressStart& progress = {});

// Writes RESULT_DIR/report.html (report/report.hpp) for a solve of the stack
// in `input`; without `light_statistics` the stack's frame pixels are not read
// (a stack solved in bands). `in_bands`: the solve kept to --memory-limit, so
// the report reads the maps a band at a time too (none kept for its passes)
// and makes its sections one at a time.
// Throws Error naming report.html when it cannot be written (the other
// results stay on disk; the command must still fail).
void write_result_report(const std::filesystem::path& result_dir, const std::filesystem::path& input,
                         bool light_statistics = true, bool in_bands = false);

}  // namespace lightstage::pipeline
