#include "lightstage/pipeline/solve_bands.hpp"

#include "band_solver.hpp"
#include "band_spill.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/host/io/output_folder.hpp"
#include "lightstage/host/report/report.hpp"
#include "lightstage/pipeline/memory_budget.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <optional>

namespace lightstage::pipeline {
namespace {

// Bytes per pixel, beside the images: a pixel's observations (a float and a
// saturation flag per image, its place, chroma, near-light point) and the
// maps a solve makes of it (normals, albedo, residual, solved, confidence and
// its error map, chroma, choice).
constexpr std::size_t kObservationBytes = 5;  // per image
constexpr std::size_t kPixelBytes = 8 + 12 + 24 + 1;
constexpr std::size_t kMapBytes = 12 + 4 + 4 + 1 + 4 + 4 + 12 + 1;
// Held for the whole image while bands are solved: the stack's and the region's masks, the background
// sample, the solved map the output writer keeps, the angular error of each pixel against ground truth.
constexpr std::size_t kHeldBytes = 16;
constexpr std::size_t kUnknownPixelBytes = 12;  // float RGB, the most a frame pixel takes
// The program itself before it reads a stack: code, libraries, allocator (65-78 MB measured for
// `lightstage`).
constexpr std::size_t kProcessBytes = std::size_t{96} << 20;
constexpr std::size_t kGroundTruthBytes = 6 + 12 + 12;
// Per image of a sampled pixel: its value, light and flag, and one model's row of it (a double per
// coefficient, the value, the image, whether lit; reflectance/relighting_fit.cpp).
constexpr std::size_t kSampleBytes = 8 + 24 + 1 + 8 + 4 + 1;
constexpr std::size_t kSampleBytesPerTerm = 8;

constexpr std::array kBandMethods = {"l2",  "robust",   "monotonic",   "rpca",    "l1",
                                     "sbl", "bilinear", "biquadratic", "bicubic", "auto"};
// Tiles are solved by jobs that do not see each other: only the methods with no object-wide
// estimate beyond the shadow threshold (which `--tile prepare` shares).
constexpr std::array kTileMethods = {"l2", "robust", "monotonic", "l1", "sbl"};

}  // namespace

nlohmann::json BandPlan::to_json() const {
  return {{"whole_bytes", whole_bytes}, {"fixed_bytes", fixed_bytes},
          {"row_bytes", row_bytes},     {"read_ahead_row_bytes", read_ahead_row_bytes},
          {"read_ahead", read_ahead},   {"report_bytes", report_bytes},
          {"band_rows", band_rows},     {"bands", bands}};
}

BandPlan plan_bands(const io::StackOutline& stack, std::size_t memory_limit, int coefficient_terms,
                    std::size_t working_bytes) {
  const cv::Size size = stack.size;
  const auto width = static_cast<std::size_t>(size.width);
  const auto pixels = width * static_cast<std::size_t>(size.height);
  const std::size_t images = stack.images;
  // Frames and their darks decoded (float RGB where the headers do not say),
  // ground-truth normals (16-bit RGB and their float decoding).
  const auto pixel_bytes =
      static_cast<std::size_t>(stack.pixel_bytes > 0 ? stack.pixel_bytes : kUnknownPixelBytes);
  const std::size_t decoded = width * (pixel_bytes * (images + stack.dark_files) + kGroundTruthBytes);
  BandPlan plan;
  plan.limit_bytes = memory_limit;
  // A refit band holds its coefficients three times: the solver's, read back from the spill, and refitted.
  const auto coefficients = static_cast<std::size_t>(std::max(coefficient_terms, 0)) * sizeof(float) * 3;
  plan.read_ahead_row_bytes = decoded;
  plan.row_bytes = decoded + width * (kObservationBytes * images + kPixelBytes + kMapBytes + coefficients);
  // The program and what is held for the whole image; the output maps go to their files band by band.
  plan.fixed_bytes = kProcessBytes + pixels * kHeldBytes + working_bytes;
  // The relighting refit's sample: each pixel's values, lights and flags (RelightingSample).
  if (coefficient_terms > 0)
    plan.fixed_bytes += static_cast<std::size_t>(RelightingFitOptions{}.sample_pixels) * images *
                        (kSampleBytes + kSampleBytesPerTerm * static_cast<std::size_t>(coefficient_terms));
  plan.report_bytes = kProcessBytes + report::report_memory_bytes(size.width, size.height);
  plan.whole_bytes =
      std::max(plan.fixed_bytes + plan.row_bytes * static_cast<std::size_t>(size.height), plan.report_bytes);
  if (plan.whole_bytes <= memory_limit) {
    plan.band_rows = size.height;
    plan.bands = 1;
    return plan;
  }
  // In bands the report reads the maps a band at a time too (write_result_report).
  report::ReportOptions banded_report;
  banded_report.kept_map_bytes = 0;
  plan.report_bytes = kProcessBytes + report::report_memory_bytes(size.width, size.height, banded_report);
  if (memory_limit < plan.fixed_bytes + plan.row_bytes)
    fail(
        "--memory-limit {}: too small for this stack ({}x{}, {} images): what is held for the whole image "
        "takes {} and a band of one row {} more",
        describe_bytes(memory_limit), size.width, size.height, images, describe_bytes(plan.fixed_bytes),
        describe_bytes(plan.row_bytes));
  // The next band read while one is solved, where a band of a row and the next one's row fit; else the
  // bands are read one after the other.
  const std::size_t room = memory_limit - plan.fixed_bytes;
  const std::size_t ahead_rows = room / (plan.row_bytes + plan.read_ahead_row_bytes);
  const std::size_t rows = ahead_rows > 0 ? ahead_rows : room / plan.row_bytes;
  plan.band_rows = static_cast<int>(std::min<std::size_t>(rows, static_cast<std::size_t>(size.height)));
  plan.bands = (size.height + plan.band_rows - 1) / plan.band_rows;
  plan.read_ahead = ahead_rows > 0 && plan.bands > 1;
  return plan;
}

bool solves_in_bands(const std::string& method) {
  return std::find(kBandMethods.begin(), kBandMethods.end(), method) != kBandMethods.end();
}

std::string band_methods_text() { return fmt::format("{}", fmt::join(kBandMethods, ", ")); }

bool solves_in_tiles(const SolveSettings& settings) {
  return std::find(kTileMethods.begin(), kTileMethods.end(), settings.method) != kTileMethods.end() &&
         !falloff_estimating_options(settings);
}

std::string tile_methods_text() { return fmt::format("{}", fmt::join(kTileMethods, ", ")); }

SolveReport solve_folder_in_bands(const std::filesystem::path& input, const SolveSettings& settings,
                                  const std::filesystem::path& out, const SolveCalibration& calibration,
                                  io::StackBands& stack, const BandPlan& plan) {
  bands::BandSolver solver(input, settings, calibration, stack, plan);
  io::require_separate_output(out, {input});
  logger("host")->info("{}: {} to solve whole; solving in {} bands of {} rows", input.string(),
                       describe_bytes(plan.whole_bytes), solver.plan().bands, solver.plan().band_rows);
  if (plan.report_bytes > plan.limit_bytes)
    logger("host")->warn("{}: the report will take about {}, over --memory-limit {}", input.string(),
                         describe_bytes(plan.report_bytes), describe_bytes(plan.limit_bytes));
  // l2 dropping no shadows reads the stack once: the threshold it only
  // records is gathered from the bands it solves.
  const bool gather = solver.gather_shadow_threshold();
  const ShadowThreshold threshold = gather ? ShadowThreshold{} : solver.shadow_threshold();
  solver.estimate_falloff(threshold);
  AngularErrorAccumulator error;
  bool ground_truth = false;
  io::SolveOutputWriter writer(out, solver.size());
  const bands::BandSolver::BandSink write = [&writer](const SolveResult& band, int rows) {
    if (band.normals.empty())
      writer.add_empty(rows);
    else
      writer.add(band);
  };
  SolveResult result;
  if (!method_refits_relighting(settings.method)) {
    result = solver.solve_rows(0, solver.size().height, threshold, error, ground_truth, write);
  } else {
    // The refit's model needs a sample of every band's normals first: the bands wait on disk.
    bands::BandSpill spill(out);
    std::size_t refittable = 0;
    result = solver.solve_rows(0, solver.size().height, threshold, error, ground_truth,
                               [&](const SolveResult& band, int rows) {
                                 if (!band.normals.empty())
                                   refittable += count_refittable_pixels(band.normals, band.solved);
                                 spill.write(band, rows);
                               });
    solver.refit_relighting(spill, refittable, result, write);
  }
  if (gather)
    result.parameters["shadow_threshold_choice"] =
        shadow_threshold_choice(solver.gathered_shadow_threshold(), settings);
  nlohmann::json extra = solver.describe();
  if (solver.light_statistics()) extra["light_statistics"] = solver.light_statistics()->summary_json();
  return bands::write_band_solve(input, out, writer, result, extra,
                                 ground_truth ? std::optional(error.stats()) : std::nullopt);
}

}  // namespace lightstage::pipeline
