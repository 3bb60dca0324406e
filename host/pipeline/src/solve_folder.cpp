#include "lightstage/pipeline/solve_folder.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/common/parallel.hpp"
#include "lightstage/host/calibration/apply_calibration.hpp"
#include "lightstage/host/io/output_folder.hpp"
#include "lightstage/host/io/solve_output.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/host/report/light_statistics.hpp"
#include "lightstage/host/report/report.hpp"
#include "lightstage/host/stack_response.hpp"
#include "lightstage/pipeline/memory_budget.hpp"
#include "lightstage/pipeline/solve_bands.hpp"
#include "lightstage/pipeline/solve_methods.hpp"
#include "stack_region.hpp"

#include <fmt/format.h>

namespace lightstage::pipeline {

void write_result_report(const std::filesystem::path& result_dir, const std::filesystem::path& input,
                         bool light_statistics, bool in_bands) {
  const std::filesystem::path file = result_dir / "report.html";
  return_free_memory();  // what the solve freed is the report's now
  try {
    report::ReportOptions options;
    options.stack = input;
    options.light_statistics = light_statistics;
    if (in_bands) {  // within --memory-limit: no maps kept, one section at a time
      options.kept_map_bytes = 0;
      options.threads = 1;
    }
    const auto written = report::write_report(result_dir, file, options);
    logger("host")->info("report: {} ({:.1f} MB)", written.file.string(),
                         static_cast<double>(written.bytes) / 1e6);
  } catch (const Error& e) {
    // Said even with --quiet: a run that promised a report must not look complete without it.
    throw Error(fmt::format("{}: report not written ({}); the other results are in {}", file.string(),
                            e.what(), result_dir.string()));
  }
}

nlohmann::json set_light_model(const std::filesystem::path& input, const ImageStack& stack,
                               const std::optional<calibration::StackCalibration>& applied,
                               const SolveCalibration& calibration, Observations& observations, bool warn) {
  std::string light_model = "distant";
  std::string why = calibration.distant ? "--distant-lights" : "no LED positions";
  if (applied && !calibration.distant && calibration::set_near_lights(*applied, observations))
    light_model = "near (calibration)";
  if (!calibration.distant && light_model == "distant") {
    std::string why_not;
    if (calibration::set_stack_near_lights(input, stack, observations, &why_not)) {
      light_model = "near (stack)";
    } else if (why_not.find("has no led_position_mm") == std::string::npos) {
      // Positions the stack holds yet cannot use change the normals: say so, unless the light was distant.
      if (warn && why_not.find("distant") == std::string::npos)
        logger("host")->warn("{}: LED positions not used ({}); solving with distant lights", input.string(),
                             why_not);
      why = why_not;
    }
  }
  return {{"model", light_model == "distant" ? "distant" : "near"},
          {"source", light_model == "near (calibration)" ? "calibration"
                     : light_model == "near (stack)"     ? "stack"
                                                         : why}};
}

SolveInput load_solve_input(const std::filesystem::path& input, const RadiometryOptions& radiometry,
                            const SolveCalibration& calibration, const cv::Rect& region) {
  radiometry.check();
  ImageStack stack;
  cv::Size whole;
  if (region.empty()) {
    stack = io::load_stack(input);
  } else {
    io::StackBands bands(input);
    whole = bands.size();
    stack = read_region_rows(bands, region, region.y, region.height);
  }
  const nlohmann::json response = linearise_stack(input, stack, calibration.response);
  std::optional<calibration::StackCalibration> applied;
  if (!calibration.file.empty())
    applied = calibration::apply_calibration_file(calibration.file, input, stack);
  SolveInput prepared;
  prepared.observations = make_observations(stack, radiometry);
  if (!region.empty()) {
    prepared.observations.origin = region.tl();
    prepared.observations.whole_size = whole;
  }
  prepared.shadow = estimate_shadow_threshold(stack, prepared.observations);
  prepared.ground_truth = std::move(stack.ground_truth);
  prepared.frame_files = report::frame_files(stack);
  prepared.response = response;
  prepared.light_model =
      set_light_model(input, stack, applied, calibration, prepared.observations, /*warn=*/true);
  if (applied) {
    prepared.calibration = applied->describe();
    prepared.calibration["near_lights"] = prepared.light_model["source"] == "calibration";
  }
  return prepared;
}

SolveReport solve_folder(const std::filesystem::path& input, const RadiometryOptions& radiometry,
                         const SolverFunction& solver, const std::filesystem::path& out,
                         const SolveCalibration& calibration, const cv::Rect& region) {
  io::require_separate_output(out, {input});
  const SolveInput prepared = load_solve_input(input, radiometry, calibration, region);
  const SolveResult result = solver(prepared);
  if (result.summary.pixels_solved == 0)
    fail("{}: {} solved no pixel: {}", input.string(), result.summary.method,
         result.summary.unusable_reason());
  SolveReport report;
  nlohmann::json extra = {
      {"radiometry", {{"clamp_to_one", radiometry.clamp_to_one}, {"response", prepared.response}}},
      {"lights", prepared.light_model}};
  if (!prepared.calibration.is_null()) extra["calibration"] = prepared.calibration;
  if (!region.empty()) extra["crop"] = {region.x, region.y, region.width, region.height};
  // Gathered here, from the observations in memory, so that the report need not decode the stack again.
  report::LightStatisticsTally light_statistics(prepared.frame_files,
                                                report::statistics_threshold(result.parameters));
  light_statistics.add(prepared.observations);
  extra["light_statistics"] = light_statistics.summary_json();
  if (prepared.ground_truth && !prepared.ground_truth->normals.empty()) {
    report.error =
        angular_error(result.normals, prepared.ground_truth->normals, prepared.observations.mask).stats;
    extra["error_vs_ground_truth"] = report.error->to_json();
  }
  report.summary = io::write_solve_outputs(out, result, input, extra);
  logger("host")->info("{}", result.summary.message);
  // Said after the solve, so an input error stays one line.
  logger("host")->info("lights: {} ({}); camera response: {}",
                       prepared.light_model["model"].get<std::string>(),
                       prepared.light_model["source"].get<std::string>(),
                       prepared.response["applied"].get<bool>()
                           ? "applied from " + prepared.response["source"].get<std::string>()
                       : prepared.response["source"].get<std::string>() == "capture" ? "applied at capture"
                                                                                     : "none");
  write_result_report(out, input);
  return report;
}

SolveReport solve_folder(const std::filesystem::path& input, const SolveSettings& settings,
                         const std::filesystem::path& out, const SolveCalibration& calibration,
                         const ProgressStart& progress) {
  io::require_separate_output(out, {input});
  const ThreadLimit threads(settings.threads.value_or(0));  // decoding, writing and the report too
  io::StackOutline outline = io::read_stack_outline(input);
  const cv::Rect region = solve_region(settings, outline.size, input);
  outline.size.height = region.height;  // frames are decoded full width, then cut to the region
  const BandPlan plan =
      plan_bands(outline, parse_memory_limit(settings.memory_limit), coefficient_terms(settings.method),
                 solver_working_bytes(settings, outline.images));
  if (plan.bands > 1) {
    io::StackBands stack(input);
    SolveSettings banded = settings;
    if (progress) {
      const cv::Mat& mask = stack.index().mask;
      const auto pixels =
          static_cast<std::size_t>(mask.empty() ? region.area() : cv::countNonZero(mask(region)));
      banded.set_progress(progress(solve_work(settings, pixels)));
    }
    return solve_folder_in_bands(input, banded, out, calibration, stack, plan);
  }
  return solve_folder(
      input, settings.radiometry,
      [&settings, &progress](const SolveInput& prepared) {
        SolveSettings chosen = settings;
        if (progress) chosen.set_progress(progress(solve_work(settings, prepared.observations)));
        return solve_with(prepared.observations, chosen, prepared.shadow);
      },
      out, calibration, settings.crop.empty() ? cv::Rect{} : region);
}

}  // namespace lightstage::pipeline
