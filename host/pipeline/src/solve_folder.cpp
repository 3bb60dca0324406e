#include "lightstage/pipeline/solve_folder.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/host/calibration/apply_calibration.hpp"
#include "lightstage/host/io/output_folder.hpp"
#include "lightstage/host/io/solve_output.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/host/report/report.hpp"
#include "lightstage/pipeline/solve_methods.hpp"

#include <fmt/format.h>

namespace lightstage::pipeline {

void write_result_report(const std::filesystem::path& result_dir, const std::filesystem::path& input) {
  const std::filesystem::path file = result_dir / "report.html";
  try {
    report::ReportOptions options;
    options.stack = input;
    const auto written = report::write_report(result_dir, file, options);
    logger("host")->info("report: {} ({:.1f} MB)", written.file.string(),
                         static_cast<double>(written.bytes) / 1e6);
  } catch (const Error& e) {
    // Said even with --quiet: a run that promised a report must not look complete without it.
    throw Error(fmt::format("{}: report not written ({}); the other results are in {}", file.string(),
                            e.what(), result_dir.string()));
  }
}

SolveInput load_solve_input(const std::filesystem::path& input, const RadiometryOptions& radiometry,
                            const SolveCalibration& calibration) {
  radiometry.check();
  ImageStack stack = io::load_stack(input);
  std::optional<calibration::StackCalibration> applied;
  if (!calibration.file.empty())
    applied = calibration::apply_calibration_file(calibration.file, input, stack);
  SolveInput prepared;
  prepared.observations = make_observations(stack, radiometry);
  prepared.shadow = estimate_shadow_threshold(stack, prepared.observations);
  prepared.ground_truth = std::move(stack.ground_truth);
  if (applied) {
    const bool near = !calibration.distant && calibration::set_near_lights(*applied, prepared.observations);
    prepared.calibration = applied->describe();
    prepared.calibration["near_lights"] = near;
  }
  return prepared;
}

SolveReport solve_folder(const std::filesystem::path& input, const RadiometryOptions& radiometry,
                         const SolverFunction& solver, const std::filesystem::path& out,
                         const SolveCalibration& calibration) {
  io::require_separate_output(out, {input});
  const SolveInput prepared = load_solve_input(input, radiometry, calibration);
  const SolveResult result = solver(prepared);
  if (result.summary.pixels_solved == 0)
    fail("{}: {} solved no pixel: {}", input.string(), result.summary.method,
         result.summary.unusable_reason());
  SolveReport report;
  nlohmann::json extra = {{"radiometry", {{"clamp_to_one", radiometry.clamp_to_one}}}};
  if (!prepared.calibration.is_null()) extra["calibration"] = prepared.calibration;
  if (prepared.ground_truth && !prepared.ground_truth->normals.empty()) {
    report.error =
        angular_error(result.normals, prepared.ground_truth->normals, prepared.observations.mask).stats;
    extra["error_vs_ground_truth"] = report.error->to_json();
  }
  report.summary = io::write_solve_outputs(out, result, input, extra);
  logger("host")->info("{}", result.summary.message);
  write_result_report(out, input);
  return report;
}

SolveReport solve_folder(const std::filesystem::path& input, const SolveSettings& settings,
                         const std::filesystem::path& out, const SolveCalibration& calibration) {
  return solve_folder(
      input, settings.radiometry,
      [&settings](const SolveInput& prepared) {
        return solve_with(prepared.observations, settings, prepared.shadow);
      },
      out, calibration);
}

}  // namespace lightstage::pipeline
