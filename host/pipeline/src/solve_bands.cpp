#include "lightstage/pipeline/solve_bands.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/host/calibration/apply_calibration.hpp"
#include "lightstage/host/eval/angular_error.hpp"
#include "lightstage/host/io/output_folder.hpp"
#include "lightstage/host/io/solve_output.hpp"
#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/shadow_threshold.hpp"
#include "lightstage/host/solvers/sparse_regression.hpp"
#include "lightstage/host/stack_response.hpp"
#include "lightstage/pipeline/memory_budget.hpp"
#include "lightstage/pipeline/solve_methods.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
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
constexpr std::size_t kUnknownPixelBytes = 12;
// The program itself before it reads a stack: code, libraries, allocator (65-78 MB measured for
// `lightstage`).
constexpr std::size_t kProcessBytes = std::size_t{96} << 20;  // float RGB, the most a frame pixel takes
constexpr std::size_t kGroundTruthBytes = 6 + 12 + 12;

constexpr std::array kBandMethods = {"l2", "robust", "monotonic", "l1", "sbl"};

// Pastes a band's map into the whole image's, allocating it (zeros) at the first band that has one.
void paste(const cv::Mat& band, int y0, cv::Size size, cv::Mat& whole) {
  if (band.empty()) return;
  if (whole.empty()) whole = cv::Mat(size, band.type(), cv::Scalar::all(0));
  band.copyTo(whole.rowRange(y0, y0 + band.rows));
}

const SolveFact* find_fact(const std::vector<SolveFact>& facts, const std::string& key) {
  const auto it = std::find_if(facts.begin(), facts.end(), [&](const SolveFact& f) { return f.key == key; });
  return it == facts.end() ? nullptr : &*it;
}

// The bands' results as one: maps pasted, counts added, the facts that
// depend on the data (normals facing away, l1/sbl iterations per pixel) merged.
class BandResults {
 public:
  explicit BandResults(cv::Size size) : size_(size) {}

  void add(const SolveResult& band, int y0) {
    if (!started_) {
      whole_.parameters = band.parameters;
      whole_.reflectance = band.reflectance;
      whole_.choices = band.choices;
      whole_.summary.method = band.summary.method;
      whole_.summary.settings = band.summary.settings;
      started_ = true;
    }
    paste(band.normals, y0, size_, whole_.normals);
    paste(band.albedo, y0, size_, whole_.albedo);
    paste(band.residual, y0, size_, whole_.residual);
    paste(band.solved, y0, size_, whole_.solved);
    paste(band.confidence, y0, size_, whole_.confidence);
    paste(band.chroma, y0, size_, whole_.chroma);
    paste(band.coefficients, y0, size_, whole_.coefficients);
    paste(band.choice, y0, size_, whole_.choice);
    SolveSummary& s = whole_.summary;
    const SolveSummary& b = band.summary;
    s.pixels_in_mask += b.pixels_in_mask;
    s.pixels_solved += b.pixels_solved;
    s.pixels_rejected_too_few_observations += b.pixels_rejected_too_few_observations;
    s.pixels_rejected_degenerate += b.pixels_rejected_degenerate;
    s.seconds += b.seconds;
    if (const SolveFact* f = find_fact(b.findings, "normals_facing_away"))
      facing_away_ += f->value.get<std::size_t>();
    // A band's mean of whole iteration counts gives back its total exactly, so the mean over all bands is
    // the whole image's to the last bit.
    if (const SolveFact* f = find_fact(b.settings, "iterations"))
      iterations_ += std::round(f->value.get<double>() * static_cast<double>(b.pixels_solved));
  }

  SolveResult finish() {
    // Maps a method always writes stay whole-image sized when no band had a pixel.
    for (cv::Mat* map : {&whole_.normals, &whole_.albedo, &whole_.residual, &whole_.solved}) {
      if (!map->empty()) continue;
      const int type = map == &whole_.normals ? CV_32FC3 : map == &whole_.solved ? CV_8UC1 : CV_32FC1;
      *map = cv::Mat(size_, type, cv::Scalar::all(0));
    }
    SolveSummary& s = whole_.summary;
    s.findings = {facing_away_fact(facing_away_)};
    for (SolveFact& fact : s.settings) {
      if (fact.key == "iterations")
        fact = iterations_per_pixel_fact(
            s.pixels_solved > 0 ? iterations_ / static_cast<double>(s.pixels_solved) : 0.0);
    }
    s.message = s.format_message();
    return std::move(whole_);
  }

 private:
  cv::Size size_;
  SolveResult whole_;
  bool started_ = false;
  std::size_t facing_away_ = 0;
  double iterations_ = 0;
};

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

SolveReport solve_folder_in_bands(const std::filesystem::path& input, const SolveSettings& settings,
                                  const std::filesystem::path& out, const SolveCalibration& calibration,
                                  io::StackBands& stack, const BandPlan& plan) {
  if (!solves_in_bands(settings.method))
    fail(
        "{}: --method {} needs the whole image in memory (about {}, over --memory-limit): it solves in "
        "bands only with {}",
        input.string(), settings.method, describe_bytes(plan.whole_bytes), fmt::join(kBandMethods, ", "));
  io::require_separate_output(out, {input});
  settings.radiometry.check();
  const cv::Size size = stack.size();
  logger("host")->info("{}: {} to solve whole; solving in {} bands of {} rows", input.string(),
                       describe_bytes(plan.whole_bytes), plan.bands, plan.band_rows);

  // What applies to every band, decided once: the camera response, the
  // calibration's lights (frame fields only), the background sample.
  ImageStack meta = stack.index();
  const StackResponse response = choose_stack_response(input, calibration.response);
  std::optional<calibration::StackCalibration> applied;
  if (!calibration.file.empty()) applied = calibration::apply_calibration_file(calibration.file, input, meta);
  const cv::Mat background = background_sample_mask(meta.mask);
  const std::size_t total_pixels = meta.mask.empty() ? static_cast<std::size_t>(size.area())
                                                     : static_cast<std::size_t>(cv::countNonZero(meta.mask));

  // Visits every band top to bottom: its frames (calibrated, linearised) and its observations.
  const auto for_each_band = [&](const std::function<void(ImageStack&, Observations&, int)>& visit) {
    std::size_t first_pixel = 0;
    for (int y0 = 0; y0 < size.height; y0 += plan.band_rows) {
      const int rows = std::min(plan.band_rows, size.height - y0);
      ImageStack band = stack.read_band(y0, rows);
      for (std::size_t i = 0; i < band.frames.size(); ++i) {
        Frame frame = meta.frames[i];
        frame.image = band.frames[i].image;
        frame.dark = band.frames[i].dark;
        band.frames[i] = std::move(frame);
      }
      if (response.response) apply_response(*response.response, band, input.string());
      Observations observations = make_observations(band, settings.radiometry);
      observations.origin = {0, y0};
      observations.whole_size = size;
      observations.first_pixel = first_pixel;
      first_pixel += observations.pixel_count();
      visit(band, observations, y0);
    }
  };

  // Pass 1: the shadow threshold's samples, as a whole-image solve draws them.
  ShadowThreshold threshold;
  if (!settings.shadow_threshold) {
    ShadowSamples samples(total_pixels);
    std::string source;
    for_each_band([&](ImageStack& band, Observations& observations, int y0) {
      if (source.empty()) source = shadow_threshold_source(band);
      samples.add_object(observations);
      if (background.empty()) return;
      band.mask = background.rowRange(y0, y0 + observations.size.height).clone();
      samples.add_background(make_observations(band));
    });
    threshold = samples.estimate(source);
  }

  // Pass 2: every band solved with it, pasted into the whole image's maps.
  std::optional<SolvePlan> solve_plan;
  nlohmann::json light_model;
  BandResults results(size);
  AngularErrorAccumulator error;
  bool ground_truth = false;
  for_each_band([&](ImageStack& band, Observations& observations, int y0) {
    const nlohmann::json model =
        set_light_model(input, band, applied, calibration, observations, /*warn=*/light_model.is_null());
    if (light_model.is_null()) light_model = model;
    if (!solve_plan) solve_plan = plan_solve(observations, settings, threshold);
    if (observations.pixel_count() == 0) return;
    const SolveResult result = solve_planned(observations, *solve_plan, /*refit_relighting=*/false);
    results.add(result, y0);
    if (band.ground_truth && !band.ground_truth->normals.empty()) {
      error.add(result.normals, band.ground_truth->normals, observations.mask);
      ground_truth = true;
    }
  });
  SolveResult result = results.finish();
  if (result.summary.pixels_solved == 0)
    fail("{}: {} solved no pixel: {}", input.string(), result.summary.method,
         result.summary.unusable_reason());

  SolveReport report;
  nlohmann::json extra = {
      {"radiometry",
       {{"clamp_to_one", settings.radiometry.clamp_to_one}, {"response", response.description}}},
      {"lights", light_model},
      {"bands", plan.to_json()}};
  if (applied) {
    extra["calibration"] = applied->describe();
    extra["calibration"]["near_lights"] = light_model.value("source", "") == "calibration";
  }
  if (ground_truth) {
    report.error = error.stats();
    extra["error_vs_ground_truth"] = report.error->to_json();
  }
  report.summary = io::write_solve_outputs(out, result, input, extra);
  logger("host")->info("{}", result.summary.message);
  // Per-light statistics would read the whole stack at once: the report leaves them out (and says so).
  write_result_report(out, input, /*light_statistics=*/false);
  return report;
}

}  // namespace lightstage::pipeline
