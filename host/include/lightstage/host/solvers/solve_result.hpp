#pragma once
// What every photometric-stereo solver returns: per-pixel maps plus a summary
// of what was solved, what was rejected and why, and whether the result is
// usable at all.

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace lightstage {

// Optional progress report of a solver: called with the number of items (pixels,
// or cost evaluations for shape-prior) it has just finished, from worker threads
// and in batches, so it must be thread-safe and cheap (e.g. Progress::advance).
// Empty = no report.
using SolveProgress = std::function<void(std::size_t items)>;

// One method-specific fact of a solve (a setting it ran with, or something it
// found beyond the pixel counts). `key` and `value` go to summary.json's
// "facts"; `text` is how the message shows it ("T_low 50%"); an empty text
// keeps the fact out of the message.
struct SolveFact {
  std::string key;
  nlohmann::json value;
  std::string text;
};

struct SolveSummary {
  // A solve that gives normals to fewer than this fraction of the mask's
  // pixels is not usable: its maps are holes with a few scattered normals,
  // whatever the cause (dark stack, wrong mask, lights that do not fit the data).
  static constexpr double kMinUsableFraction = 0.01;

  std::string method;              // e.g. "l2"
  std::size_t pixels_in_mask = 0;  // pixels the solver was given
  std::size_t pixels_solved = 0;   // pixels with a normal
  std::size_t pixels_rejected_too_few_observations = 0;
  std::size_t pixels_rejected_degenerate = 0;  // near-coplanar lights or zero solution
  double seconds = 0;                          // wall time of the solve
  std::vector<SolveFact> settings;             // how the method ran: "(T_low 50%, ...)" after its name
  std::vector<SolveFact> findings;             // what else it found: after the pixel counts
  // format_message() when the solver finished, for callers that log it.
  std::string message;

  // The one human-readable line: method, settings, counts, seconds, findings,
  // rejections and, when not usable, why.
  std::string format_message() const;
  // Why the result is not usable, empty when it is: the mask was empty, no
  // pixel was solved (every pixel degenerate = the lights are degenerate;
  // every pixel short of observations), or under kMinUsableFraction solved.
  std::string unusable_reason() const;
  bool usable() const { return unusable_reason().empty(); }
  // Counts, seconds, message, "usable", "unusable_reason" (only when not
  // usable) and "facts" (settings and findings by key).
  nlohmann::json to_json() const;
};

// A normal facing away from the camera (z < 0) as every solve reports it: on
// the horizon in its own azimuth, or the view axis when it has none.
cv::Vec3f on_horizon(const cv::Vec3f& n);

struct SolveResult {
  cv::Mat normals;   // CV_32FC3 (x, y, z), unit where solved, zero elsewhere
  cv::Mat albedo;    // CV_32FC1, zero where not solved
  cv::Mat residual;  // CV_32FC1, RMS of the fit over the observations used, zero where not solved
  cv::Mat solved;    // CV_8UC1, 255 where solved
  // Optional per-pixel outputs (empty when a method does not produce them):
  cv::Mat confidence;  // CV_32FC1 in [0, 1] from the predicted error (normal_confidence.hpp; solve_with)
  // CV_32FC1, degrees: the error a solver predicted itself at its answer, on the horizon where it faced
  // away (l2 solving pixel by pixel or four to a vector, L2Options::confidence); solve_with makes
  // `confidence` of it.
  cv::Mat predicted_error;
  // Colour stacks: CV_32FC3 (b, g, r, OpenCV's order) chroma of radiometry.hpp,
  // the colour albedo being albedo · chroma; 0 where not solved (solve_with).
  cv::Mat chroma;
  cv::Mat coefficients;                  // CV_32FC(k), a per-pixel reflectance model (see `reflectance`)
  nlohmann::json reflectance = nullptr;  // describes `coefficients` (model, order, term order)
  // Methods that choose per pixel (auto): CV_8UC1, 0 where not solved, k where
  // the pixel took choices[k - 1]. Written as method_map.png with counts.
  cv::Mat choice;
  std::vector<std::string> choices;
  nlohmann::json parameters = nlohmann::json::object();  // the options used, for summary.json
  SolveSummary summary;
};

}  // namespace lightstage
