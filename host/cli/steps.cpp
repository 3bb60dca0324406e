#include "steps.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/host/calibration/apply_calibration.hpp"
#include "lightstage/host/io/solve_output.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/host/report/report.hpp"

#include <fmt/format.h>

#include <chrono>

namespace lightstage::cli {

nlohmann::json simulate_to_folder(const std::filesystem::path& rig_path, const sim::SimulateOptions& options,
                                  const std::filesystem::path& out, const sim::FrameProgress& on_frames) {
  options.check();
  const Rig rig = load_rig(rig_path);
  const auto start = std::chrono::steady_clock::now();
  const ImageStack stack = sim::simulate_stack(rig, options, on_frames);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const nlohmann::json manifest = {
      {"source", "simulated"},
      {"rig", {{"name", rig.name}, {"file", rig_path.string()}}},
      {"simulation", sim::describe(rig, options)},
  };
  io::write_stack(out, stack, manifest);
  logger("host")->info("simulated {} frames of {}x{} in {:.2f} s into {}", stack.frames.size(), stack.width(),
                       stack.height(), seconds, out.string());
  return {{"stack", out.string()},
          {"frames", stack.frames.size()},
          {"width", stack.width()},
          {"height", stack.height()},
          {"seconds", seconds}};
}

void write_result_report(const std::filesystem::path& result_dir, const std::filesystem::path& input) {
  // The report is for people; a result without one is still a result, so a
  // report that cannot be written is a warning, not a failed solve.
  try {
    report::ReportOptions options;
    options.stack = input;
    const auto written = report::write_report(result_dir, result_dir / "report.html", options);
    logger("host")->info("report: {} ({:.1f} MB)", written.file.string(),
                         static_cast<double>(written.bytes) / 1e6);
  } catch (const Error& e) {
    logger("host")->warn("report not written: {}", e.what());
  }
}

SolveReport solve_folder(const std::filesystem::path& input, const RadiometryOptions& radiometry,
                         const L2Options& options, const std::filesystem::path& out) {
  options.check();
  return solve_folder(
      input, radiometry,
      [&options](const Observations& observations) { return solve_lambertian(observations, options); }, out);
}

SolveReport solve_folder(const std::filesystem::path& input, const RadiometryOptions& radiometry,
                         const SolverFunction& solver, const std::filesystem::path& out,
                         const SolveCalibration& calibration) {
  radiometry.check();
  ImageStack stack = io::load_stack(input);
  std::optional<calibration::StackCalibration> applied;
  if (!calibration.file.empty())
    applied = calibration::apply_calibration_file(calibration.file, input, stack);
  Observations observations = make_observations(stack, radiometry);
  const bool near = applied && !calibration.distant && calibration::set_near_lights(*applied, observations);
  const SolveResult result = solver(observations);
  SolveReport report;
  nlohmann::json extra = {{"radiometry", {{"clamp_to_one", radiometry.clamp_to_one}}}};
  if (applied) {
    extra["calibration"] = applied->describe();
    extra["calibration"]["near_lights"] = near;
  }
  if (stack.ground_truth && !stack.ground_truth->normals.empty()) {
    report.error = angular_error(result.normals, stack.ground_truth->normals, observations.mask).stats;
    extra["error_vs_ground_truth"] = report.error->to_json();
  }
  report.summary = io::write_solve_outputs(out, result, input, extra);
  logger("host")->info("{}", result.summary.message);
  write_result_report(out, input);
  return report;
}

void print_error_stats(const AngularErrorStats& stats) {
  fmt::print(
      "angular error over {} pixels: mean {:.3f} deg, median {:.3f} deg, p90 {:.3f} deg, max {:.3f} deg",
      stats.count, stats.mean, stats.median, stats.p90, stats.max);
  if (stats.missing > 0) fmt::print(" ({} pixels without a prediction)", stats.missing);
  fmt::print("\n");
}

}  // namespace lightstage::cli
