#include "band_solver.hpp"

#include "stack_region.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/common/parallel.hpp"
#include "lightstage/host/io/solve_output.hpp"
#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/solvers/auto.hpp"
#include "lightstage/host/solvers/bipolynomial.hpp"
#include "lightstage/host/solvers/low_rank.hpp"
#include "lightstage/pipeline/memory_budget.hpp"
#include "lightstage/pipeline/solve_folder.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

namespace lightstage::pipeline::bands {
namespace {

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

// The rows of a band's part (SolveSettings::band_part_bytes): its observations
// made and visited together. Freed blocks up to 32 MB raise glibc's threshold
// for taking blocks from the heap rather than fresh pages, so after the first
// part each part's matrices reuse the pages the part before freed; a band's
// (hundreds of MB) were fresh pages the kernel zeroed first, a quarter of the
// observations' time at 24 Mpx (docs/large-captures.md). One row at least.
int part_rows(int width, std::size_t images, std::size_t part_bytes, int band_rows) {
  const std::size_t row_bytes =
      static_cast<std::size_t>(std::max(width, 1)) * std::max<std::size_t>(images, 1) * sizeof(float);
  return static_cast<int>(
      std::clamp<std::size_t>(part_bytes / row_bytes, 1, static_cast<std::size_t>(std::max(band_rows, 1))));
}

}  // namespace

void BandResults::add(const SolveResult& band, int y0) {
  if (!started_) {
    whole_.parameters = band.parameters;
    whole_.reflectance = band.reflectance;
    whole_.choices = band.choices;
    whole_.summary.method = band.summary.method;
    whole_.summary.settings = band.summary.settings;
    whole_.summary.findings = band.summary.findings;  // their order; the values are merged
    started_ = true;
  }
  if (keep_maps_) paste_maps(band, y0);
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
  const auto total = [&](const SolveFact& f) {
    return std::round(f.value.get<double>() * static_cast<double>(b.pixels_solved));
  };
  if (b.method == "rpca") {
    // Its rounds are per block, not per pixel.
    const auto blocks = find_fact(b.settings, "blocks")->value.get<std::size_t>();
    rpca_blocks_ += blocks;
    rpca_rounds_ +=
        std::round(find_fact(b.settings, "iterations")->value.get<double>() * static_cast<double>(blocks));
    rpca_rank_ = std::max(rpca_rank_, find_fact(b.settings, "rank")->value.get<int>());
  } else if (const SolveFact* f = find_fact(b.settings, "iterations")) {
    iterations_ += total(*f);
  }
  if (const SolveFact* f = find_fact(b.findings, "mean_iterations")) mean_iterations_ += total(*f);
  if (const SolveFact* f = find_fact(b.findings, "method_counts"))
    for (const auto& [name, count] : f->value.items())
      method_counts_[name] = method_counts_.value(name, std::size_t{0}) + count.get<std::size_t>();
}

void BandResults::paste_maps(const SolveResult& band, int y0) {
  for (auto [from, to] :
       {std::pair{&band.normals, &whole_.normals}, std::pair{&band.albedo, &whole_.albedo},
        std::pair{&band.residual, &whole_.residual}, std::pair{&band.solved, &whole_.solved},
        std::pair{&band.confidence, &whole_.confidence}, std::pair{&band.chroma, &whole_.chroma},
        std::pair{&band.coefficients, &whole_.coefficients}, std::pair{&band.choice, &whole_.choice}})
    paste(*from, y0, size_, *to);
}

SolveResult BandResults::finish() {
  // Maps a method always writes stay whole-image sized when no band had a pixel.
  for (cv::Mat* map : {&whole_.normals, &whole_.albedo, &whole_.residual, &whole_.solved}) {
    if (!keep_maps_ || !map->empty()) continue;
    const int type = map == &whole_.normals ? CV_32FC3 : map == &whole_.solved ? CV_8UC1 : CV_32FC1;
    *map = cv::Mat(size_, type, cv::Scalar::all(0));
  }
  SolveSummary& s = whole_.summary;
  const auto mean = [&](double sum) {
    return s.pixels_solved > 0 ? sum / static_cast<double>(s.pixels_solved) : 0.0;
  };
  for (SolveFact& fact : s.findings) {
    if (fact.key == "normals_facing_away") fact = facing_away_fact(facing_away_);
    if (fact.key == "mean_iterations") fact = mean_iterations_fact(mean(mean_iterations_));
    if (fact.key == "method_counts") fact = method_counts_fact(method_counts_, s.pixels_solved);
  }
  if (!find_fact(s.findings, "normals_facing_away")) s.findings.push_back(facing_away_fact(facing_away_));
  if (s.method == "rpca")
    s.settings = rpca_settings(
        rpca_blocks_, rpca_blocks_ > 0 ? rpca_rounds_ / static_cast<double>(rpca_blocks_) : 0, rpca_rank_);
  else
    for (SolveFact& fact : s.settings) {
      if (fact.key == "iterations") fact = iterations_per_pixel_fact(mean(iterations_));
    }
  s.message = s.format_message();
  return std::move(whole_);
}

BandSolver::BandSolver(const std::filesystem::path& input, const SolveSettings& settings,
                       const SolveCalibration& calibration, io::StackBands& stack, const BandPlan& plan)
    : input_(input), settings_(settings), calibration_(calibration), stack_(stack), plan_(plan) {
  if (!solves_in_bands(settings.method))
    fail(
        "{}: --method {} needs the whole image in memory (about {}, over --memory-limit): it solves in "
        "bands only with {}",
        input.string(), settings.method, describe_bytes(plan.whole_bytes), band_methods_text());
  settings.radiometry.check();
  region_ = solve_region(settings, stack.size(), input);
  meta_ = stack.index();
  if (!meta_.mask.empty()) meta_.mask = meta_.mask(region_).clone();
  response_ = choose_stack_response(input, calibration.response);
  if (!calibration.file.empty())
    applied_ = calibration::apply_calibration_file(calibration.file, input, meta_);
  background_ = background_sample_mask(meta_.mask);
  if (settings.method == "rpca") {
    band_ends_ = rpca_band_ends();
    int highest = 0;
    for (std::size_t b = 0; b < band_ends_.size(); ++b)
      highest = std::max(highest, band_ends_[b] - (b == 0 ? 0 : band_ends_[b - 1]));
    if (highest > plan_.band_rows) {
      logger("host")->warn(
          "{}: rpca decomposes {} rows together, more than the {} rows --memory-limit allows", input.string(),
          highest, plan_.band_rows);
      plan_.read_ahead = false;  // over the limit already: one band's frames at a time
    }
    plan_.band_rows = highest;
    plan_.bands = static_cast<int>(band_ends_.size());
    plan_.read_ahead = plan_.read_ahead && plan_.bands > 1;
  }
}

std::vector<int> BandSolver::rpca_band_ends() const {
  std::vector<std::size_t> row_pixels(static_cast<std::size_t>(size().height));
  for (int y = 0; y < size().height; ++y) row_pixels[static_cast<std::size_t>(y)] = mask_pixels(y, y + 1);
  const std::vector<int> runs = rpca_row_runs(row_pixels, settings_.rpca.block_pixels);
  std::vector<int> ends;
  int y0 = 0;
  for (std::size_t r = 0; r < runs.size(); ++r) {
    // The band takes this run, and ends here unless the next run fits in it too.
    if (r + 1 < runs.size() && runs[r + 1] - y0 <= plan_.band_rows) continue;
    ends.push_back(runs[r]);
    y0 = runs[r];
  }
  return ends;
}

std::size_t BandSolver::mask_pixels(int begin, int end) const {
  return meta_.mask.empty() ? static_cast<std::size_t>(end - begin) * static_cast<std::size_t>(size().width)
                            : static_cast<std::size_t>(cv::countNonZero(meta_.mask.rowRange(begin, end)));
}

ImageStack BandSolver::read_band(int y0, int rows) {
  ImageStack band = read_region_rows(stack_, region_, region_.y + y0, rows);
  for (std::size_t i = 0; i < band.frames.size(); ++i) {
    Frame frame = meta_.frames[i];
    frame.image = band.frames[i].image;
    frame.dark = band.frames[i].dark;
    band.frames[i] = std::move(frame);
  }
  if (response_.response) apply_response(*response_.response, band, input_.string());
  return band;
}

void BandSolver::for_each_band(int begin, int end, const BandVisit& visit) {
  // A pixel's place among the region's mask pixels seeds its random draws.
  std::size_t first_pixel = mask_pixels(0, begin);
  // rpca's bands cover the whole region (it solves in no tiles).
  if (!band_ends_.empty() && (begin != 0 || end != size().height))
    throw std::logic_error(
        fmt::format("rpca's bands cover rows 0 to {}, not {} to {}", size().height, begin, end));
  std::vector<std::pair<int, int>> bands;  // each band's first row and rows
  for (int y0 = begin; y0 < end; y0 += bands.back().second)
    bands.emplace_back(
        y0, band_ends_.empty() ? std::min(plan_.band_rows, end - y0) : band_ends_.at(bands.size()) - y0);
  const auto solve = [&](ImageStack& band, int y0, int rows) {
    // rpca's blocks need its band whole.
    const int step = band_ends_.empty()
                         ? part_rows(band.width(), band.frames.size(), settings_.band_part_bytes, rows)
                         : rows;
    for (int top = 0; top < rows; top += step) {
      ImageStack part = stack_area(band, cv::Rect(0, top, band.width(), std::min(step, rows - top)));
      Observations observations = make_observations(part, settings_.radiometry);
      observations.origin = {region_.x, region_.y + y0 + top};
      observations.whole_size = stack_.size();
      observations.first_pixel = first_pixel;
      first_pixel += observations.pixel_count();
      visit(part, observations, y0 + top);
    }
  };
  // The next band is read while this one is solved, where the plan holds two bands' frames: the
  // threads one leaves idle, at its serial steps or its last rows, decode the other's. Else a band's
  // frames go before the next band's are read.
  ImageStack band = bands.empty() ? ImageStack{} : read_band(bands.front().first, bands.front().second);
  for (std::size_t k = 0; k < bands.size(); ++k) {
    ImageStack next;
    const auto solve_this = [&] { solve(band, bands[k].first, bands[k].second); };
    const auto read_next = [&] {
      if (k + 1 < bands.size()) next = read_band(bands[k + 1].first, bands[k + 1].second);
    };
    if (plan_.read_ahead) {
      parallel_invoke({solve_this, read_next}, 0);
    } else {
      solve_this();
      band = ImageStack{};
      read_next();
    }
    band = std::move(next);
  }
}

bool BandSolver::estimates_shadow_threshold() const { return !settings_.shadow_threshold; }

void BandSolver::add_shadow_samples(ShadowSamples& samples, std::string& source, const ImageStack& band,
                                    const Observations& observations, int y0) const {
  if (source.empty()) source = shadow_threshold_source(band);
  samples.add_object(observations);
  if (background_.empty()) return;
  ImageStack background = band;  // the band's frames (their pixels shared), the background's mask
  background.mask = background_.rowRange(y0, y0 + observations.size.height).clone();
  samples.add_background(make_observations(background));
}

ShadowThreshold BandSolver::shadow_threshold() {
  if (!estimates_shadow_threshold()) return {};
  ShadowSamples samples(mask_pixels(0, size().height));
  std::string source;
  for_each_band(0, size().height, [&](ImageStack& band, Observations& observations, int y0) {
    add_shadow_samples(samples, source, band, observations, y0);
  });
  return samples.estimate(source);
}

bool BandSolver::gather_shadow_threshold() {
  if (!estimates_shadow_threshold() || settings_.drops_shadows()) return false;
  gathered_.emplace(mask_pixels(0, size().height));
  gathered_source_.clear();
  gathered_all_rows_ = false;
  return true;
}

ShadowThreshold BandSolver::gathered_shadow_threshold() const {
  if (!gathered_all_rows_)
    throw std::logic_error(
        "gathered_shadow_threshold: no solve_rows over every row since gather_shadow_threshold");
  return gathered_->estimate(gathered_source_);
}

const SolvePlan& BandSolver::plan_band(ImageStack& band, Observations& observations,
                                       const ShadowThreshold& threshold) {
  const nlohmann::json model =
      set_light_model(input_, band, applied_, calibration_, observations, /*warn=*/light_model_.is_null());
  if (light_model_.is_null()) light_model_ = model;
  if (!solve_plan_) solve_plan_ = plan_solve(observations, settings_, threshold);
  return *solve_plan_;
}

void BandSolver::estimate_falloff(const ShadowThreshold& threshold) {
  if (!falloff_estimating_options(settings_)) return;
  FalloffSamples samples(mask_pixels(0, size().height));
  for_each_band(0, size().height, [&](ImageStack& band, Observations& observations, int) {
    const SolvePlan& plan = plan_band(band, observations, threshold);
    samples.add(observations, *falloff_estimating_options(plan.settings));  // with the plan's threshold
  });
  if (solve_plan_) use_falloff_estimate(solve_plan_->settings, samples.estimate());
}

SolveResult BandSolver::solve_rows(int begin, int end, const ShadowThreshold& threshold,
                                   AngularErrorAccumulator& error, bool& has_ground_truth,
                                   const BandSink& sink) {
  const bool gather = gathered_.has_value();
  if (gather && (gathered_all_rows_ || begin != 0 || end != size().height))
    throw std::logic_error("solve_rows: the shadow threshold is gathered once, by a solve over every row");
  BandResults results({size().width, end - begin}, /*keep_maps=*/false);
  for_each_band(begin, end, [&](ImageStack& band, Observations& observations, int y0) {
    if (gather) add_shadow_samples(*gathered_, gathered_source_, band, observations, y0);
    const SolvePlan& plan = plan_band(band, observations, threshold);
    if (observations.pixel_count() == 0) {
      sink(SolveResult{}, observations.size.height);
      return;
    }
    const SolveResult result = solve_planned(observations, plan, /*refit_relighting=*/false);
    results.add(result, y0 - begin);
    sink(result, observations.size.height);
    if (!light_statistics_)
      light_statistics_.emplace(report::frame_files(meta_), report::statistics_threshold(result.parameters));
    light_statistics_->add(observations);
    if (band.ground_truth && !band.ground_truth->normals.empty()) {
      error.add(result.normals, band.ground_truth->normals, observations.mask);
      has_ground_truth = true;
    }
  });
  gathered_all_rows_ = gather;
  return results.finish();
}

void BandSolver::refit_relighting(BandSpill& spill, std::size_t refittable, SolveResult& result,
                                  const BandSink& sink) {
  const RelightingFitOptions options = relighting_fit_options(result, *solve_plan_);
  RelightingSample sample(refittable, options);
  int rows = 0;
  spill.rewind();
  for_each_band(0, size().height, [&](ImageStack& band, Observations& observations, int) {
    const SolveResult solved = spill.read(rows);
    if (solved.normals.empty()) return;
    plan_band(band, observations, solve_plan_->threshold);
    sample.add(observations, solved.normals, solved.solved);
  });
  RelightingFit fit = fit_relighting_model(sample, options);
  nlohmann::json terms = result.reflectance;  // the coefficients' names for the writer; pixels counted below
  describe_relighting_fit(fit, terms);
  spill.rewind();
  for_each_band(0, size().height, [&](ImageStack& band, Observations& observations, int) {
    SolveResult solved = spill.read(rows);
    if (solved.normals.empty()) {
      sink(solved, rows);
      return;
    }
    plan_band(band, observations, solve_plan_->threshold);
    solved.coefficients =
        refit_coefficients(observations, solved.normals, solved.solved, fit, options, solved.coefficients);
    solved.reflectance = terms;
    solved.choices = result.choices;  // the spill holds maps only
    sink(solved, rows);
  });
  describe_relighting_fit(fit, result.reflectance);
}

nlohmann::json BandSolver::describe() const {
  nlohmann::json extra = {
      {"radiometry",
       {{"clamp_to_one", settings_.radiometry.clamp_to_one}, {"response", response_.description}}},
      {"lights", light_model_},
      {"bands", plan_.to_json()}};
  // rpca's bands are solved whole.
  extra["bands"]["part_rows"] = band_ends_.empty() ? part_rows(size().width, meta_.frames.size(),
                                                               settings_.band_part_bytes, plan_.band_rows)
                                                   : plan_.band_rows;
  if (region_.size() != stack_.size()) extra["crop"] = {region_.x, region_.y, region_.width, region_.height};
  if (applied_) {
    extra["calibration"] = applied_->describe();
    extra["calibration"]["near_lights"] = light_model_.value("source", "") == "calibration";
  }
  return extra;
}

SolveReport write_band_solve(const std::filesystem::path& input, const std::filesystem::path& out,
                             io::SolveOutputWriter& writer, const SolveResult& result, nlohmann::json extra,
                             const std::optional<AngularErrorStats>& error) {
  if (result.summary.pixels_solved == 0)
    fail("{}: {} solved no pixel: {}", input.string(), result.summary.method,
         result.summary.unusable_reason());
  SolveReport report;
  if (error) {
    report.error = error;
    extra["error_vs_ground_truth"] = error->to_json();
  }
  report.summary = writer.finish(result, input, extra);
  logger("host")->info("{}", result.summary.message);
  write_result_report(out, input, /*light_statistics=*/extra.contains("light_statistics"), /*in_bands=*/true);
  return report;
}

}  // namespace lightstage::pipeline::bands
