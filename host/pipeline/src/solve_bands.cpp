#include "lightstage/pipeline/solve_bands.hpp"

#include "band_solver.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/host/io/output_folder.hpp"
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
// The whole image's maps while they are written and the report is made of them (encoded images held in
// memory, measured).
constexpr std::size_t kWritingBytes = 100;
constexpr std::size_t kUnknownPixelBytes = 12;  // float RGB, the most a frame pixel takes
// The program itself before it reads a stack: code, libraries, allocator (65-78 MB measured for
// `lightstage`).
constexpr std::size_t kProcessBytes = std::size_t{96} << 20;
constexpr std::size_t kGroundTruthBytes = 6 + 12 + 12;

constexpr std::array kBandMethods = {"l2", "robust", "monotonic", "l1", "sbl"};

}  // namespace

nlohmann::json BandPlan::to_json() const {
  return {{"whole_bytes", whole_bytes},
          {"fixed_bytes", fixed_bytes},
          {"row_bytes", row_bytes},
          {"band_rows", band_rows},
          {"bands", bands}};
}

BandPlan plan_bands(const io::StackOutline& stack, std::size_t memory_limit) {
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
  plan.row_bytes = decoded + width * (kObservationBytes * images + kPixelBytes + kMapBytes);
  // The program, the whole image's maps, the mask and the background sample, and the writing of the maps.
  plan.fixed_bytes = kProcessBytes + pixels * (kMapBytes + 2 + kWritingBytes);
  plan.whole_bytes =
      kProcessBytes + plan.row_bytes * static_cast<std::size_t>(size.height) + pixels * kWritingBytes;
  if (plan.whole_bytes <= memory_limit) {
    plan.band_rows = size.height;
    plan.bands = 1;
    return plan;
  }
  if (memory_limit < plan.fixed_bytes + plan.row_bytes)
    fail(
        "--memory-limit {}: too small for this stack ({}x{}, {} images): its output maps take {} and a band "
        "of one row {} more",
        describe_bytes(memory_limit), size.width, size.height, images, describe_bytes(plan.fixed_bytes),
        describe_bytes(plan.row_bytes));
  plan.band_rows = static_cast<int>(std::min<std::size_t>((memory_limit - plan.fixed_bytes) / plan.row_bytes,
                                                          static_cast<std::size_t>(size.height)));
  plan.bands = (size.height + plan.band_rows - 1) / plan.band_rows;
  return plan;
}

bool solves_in_bands(const std::string& method) {
  return std::find(kBandMethods.begin(), kBandMethods.end(), method) != kBandMethods.end();
}

std::string band_methods_text() { return fmt::format("{}", fmt::join(kBandMethods, ", ")); }

SolveReport solve_folder_in_bands(const std::filesystem::path& input, const SolveSettings& settings,
                                  const std::filesystem::path& out, const SolveCalibration& calibration,
                                  io::StackBands& stack, const BandPlan& plan) {
  bands::BandSolver solver(input, settings, calibration, stack, plan);
  io::require_separate_output(out, {input});
  logger("host")->info("{}: {} to solve whole; solving in {} bands of {} rows", input.string(),
                       describe_bytes(plan.whole_bytes), plan.bands, plan.band_rows);
  const ShadowThreshold threshold = solver.shadow_threshold();
  AngularErrorAccumulator error;
  bool ground_truth = false;
  const SolveResult result = solver.solve_rows(0, solver.size().height, threshold, error, ground_truth);
  nlohmann::json extra = solver.describe();
  if (solver.light_statistics()) extra["light_statistics"] = solver.light_statistics()->summary_json();
  return bands::write_band_solve(input, out, result, extra,
                                 ground_truth ? std::optional(error.stats()) : std::nullopt);
}

}  // namespace lightstage::pipeline
