#pragma once
// What a stack solved in bands (solve_bands.cpp) and the tile jobs of
// `solve --tile` (solve_tiles.cpp) share: the passes over a stack's rows and
// the bands' results made into one.

#include "band_spill.hpp"

#include "lightstage/host/calibration/apply_calibration.hpp"
#include "lightstage/host/eval/angular_error.hpp"
#include "lightstage/host/io/solve_output_writer.hpp"
#include "lightstage/host/io/stack_bands.hpp"
#include "lightstage/host/report/light_statistics.hpp"
#include "lightstage/host/shadow_threshold.hpp"
#include "lightstage/host/stack_response.hpp"
#include "lightstage/pipeline/solve_bands.hpp"
#include "lightstage/pipeline/solve_methods.hpp"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace lightstage::pipeline::bands {

// Results of bands (or of tiles, each itself the result of its bands) made
// into the whole image's: counts added, the facts that depend on the data
// (normals facing away, iterations per pixel, auto's method counts) merged
// exactly, and with
// `keep_maps` the maps pasted at their rows (a tile job's; a whole image's
// maps go to a SolveOutputWriter band by band instead).
class BandResults {
 public:
  BandResults(cv::Size size, bool keep_maps) : size_(size), keep_maps_(keep_maps) {}

  // `band` holds rows [y0, y0 + band.normals.rows) of the whole image.
  void add(const SolveResult& band, int y0);
  SolveResult finish();

 private:
  void paste_maps(const SolveResult& band, int y0);

  cv::Size size_;
  bool keep_maps_;
  SolveResult whole_;
  bool started_ = false;
  std::size_t facing_away_ = 0;
  double iterations_ = 0;        // l1/sbl's setting, in total over the pixels
  double mean_iterations_ = 0;   // the bi-polynomial's finding, in total
  std::size_t rpca_blocks_ = 0;  // rpca's blocks, their ALM rounds in total, the highest rank
  double rpca_rounds_ = 0;
  int rpca_rank_ = 0;
  nlohmann::json method_counts_ = nlohmann::json::object();
};

// A stack solved band by band. What applies to every band is decided once, at
// construction: the camera response, the calibration's lights, the
// background sample of the shadow threshold.
class BandSolver {
 public:
  // Throws InputError for a method that does not solve in bands (naming the
  // memory it needs whole and --memory-limit) and for what radiometry and the
  // calibration refuse.
  BandSolver(const std::filesystem::path& input, const SolveSettings& settings,
             const SolveCalibration& calibration, io::StackBands& stack, const BandPlan& plan);

  // Whether the shadow threshold is estimated from the data (from every row):
  // not with --shadow-threshold.
  bool estimates_shadow_threshold() const;
  // Pass 1: the threshold a whole-image solve estimates, from every row
  // (with --shadow-threshold, a default the flag's value replaces: no pass).
  ShadowThreshold shadow_threshold();
  // For a solve that estimates the threshold but drops no shadows
  // (SolveSettings::drops_shadows: l2), which only records it; returns
  // whether this is one. The next solve_rows, over every row,
  // gathers it from the bands it reads (no pass of its own), and
  // gathered_shadow_threshold() then gives what shadow_threshold() would.
  bool gather_shadow_threshold();
  ShadowThreshold gathered_shadow_threshold() const;
  // Pass 2, for a method that estimates the object's incidence fall-off
  // (falloff_estimating_options): that estimate from every row, given to
  // every band's solve. No pass for the other methods.
  void estimate_falloff(const ShadowThreshold& threshold);

  // Each band's result in turn, top to bottom; one whose normals are empty
  // stands for `rows` rows without a pixel to solve.
  using BandSink = std::function<void(const SolveResult& band, int rows)>;
  // Pass 2: rows [begin, end) solved band by band with `threshold`, each band
  // given to `sink`; returns what the bands say together (counts, facts,
  // parameters: no maps). Their angular error against the ground truth is
  // added to `error` when the stack has one.
  SolveResult solve_rows(int begin, int end, const ShadowThreshold& threshold, AngularErrorAccumulator& error,
                         bool& has_ground_truth, const BandSink& sink);

  // The last two passes of a method whose coefficients are refitted for
  // relighting (method_refits_relighting), after solve_rows gave its bands to
  // `spill`, returned `result` and the bands hold `refittable` pixels
  // (count_refittable_pixels): the object-wide model from a sample of every
  // band, then each band's coefficients refitted to it and the band given to
  // `sink`; result.reflectance then describes the fit (what solve_planned
  // does whole).
  void refit_relighting(BandSpill& spill, std::size_t refittable, SolveResult& result, const BandSink& sink);

  // The per-light statistics of the rows solved so far (nullopt before a band with a mask pixel).
  const std::optional<report::LightStatisticsTally>& light_statistics() const { return light_statistics_; }

  // summary.json's radiometry, lights (known after solve_rows), calibration, bands and crop.
  nlohmann::json describe() const;
  // The region solved (--crop, else the whole image): rows count from its top.
  cv::Size size() const { return region_.size(); }
  // Gives the solver a progress report (SolveSettings::set_progress), for the pixels of `mask_pixels(...)`.
  void set_progress(const SolveProgress& progress) { settings_.set_progress(progress); }
  // The mask pixels of rows [begin, end) of the region.
  std::size_t mask_pixels(int begin, int end) const;
  // The plan the bands follow (rpca's bands end where its runs of rows do).
  const BandPlan& plan() const { return plan_; }

 private:
  using BandVisit = std::function<void(ImageStack& band, Observations& observations, int y0)>;
  // rpca's bands: each ends at an end of the runs of rows it decomposes together (rpca_row_runs),
  // as near the plan's height as they allow.
  std::vector<int> rpca_band_ends() const;
  // Rows [y0, y0 + rows) of the region, the frames' settings and the response applied.
  ImageStack read_band(int y0, int rows);
  void for_each_band(int begin, int end, const BandVisit& visit);
  // Adds a band's object and background samples to the threshold's (and the
  // stack's source of it, at the first band).
  void add_shadow_samples(ShadowSamples& samples, std::string& source, const ImageStack& band,
                          const Observations& observations, int y0) const;
  // Sets a band's lights (warning once about what they are) and returns the
  // plan of every band's solve, made from the first band.
  const SolvePlan& plan_band(ImageStack& band, Observations& observations, const ShadowThreshold& threshold);

  std::filesystem::path input_;
  SolveSettings settings_;
  SolveCalibration calibration_;
  io::StackBands& stack_;
  BandPlan plan_;
  cv::Rect region_;
  ImageStack meta_;  // the region's mask
  StackResponse response_;
  std::optional<calibration::StackCalibration> applied_;
  cv::Mat background_;
  std::optional<ShadowSamples> gathered_;  // gather_shadow_threshold()'s samples
  std::string gathered_source_;
  bool gathered_all_rows_ = false;  // a solve_rows over every row has gathered them
  nlohmann::json light_model_;
  std::optional<SolvePlan> solve_plan_;
  std::optional<report::LightStatisticsTally> light_statistics_;
  std::vector<int> band_ends_;  // each band's end row when bands are not all band_rows high
};

// Finishes the solve folder of a result made of bands, whose maps `writer`
// was given: summary.json with `extra` and the error, and the report
// (per-light statistics only from extra's "light_statistics": the report must
// not read the whole stack at once). Throws InputError, leaving nothing, when
// no pixel was solved.
SolveReport write_band_solve(const std::filesystem::path& input, const std::filesystem::path& out,
                             io::SolveOutputWriter& writer, const SolveResult& result, nlohmann::json extra,
                             const std::optional<AngularErrorStats>& error);

}  // namespace lightstage::pipeline::bands
