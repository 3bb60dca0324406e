#pragma once
// What every photometric-stereo solver returns: per-pixel maps plus a summary
// of what was solved, what was rejected and why.

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <cstddef>
#include <functional>
#include <string>

namespace lightstage {

// Optional progress report of a solver: called with the number of items (pixels,
// or cost evaluations for shape-prior) it has just finished, from worker threads
// and in batches, so it must be thread-safe and cheap (e.g. Progress::advance).
// Empty = no report.
using SolveProgress = std::function<void(std::size_t items)>;

struct SolveSummary {
  std::string method;              // e.g. "l2"
  std::size_t pixels_in_mask = 0;  // pixels the solver was given
  std::size_t pixels_solved = 0;   // pixels with a normal
  std::size_t pixels_rejected_too_few_observations = 0;
  std::size_t pixels_rejected_degenerate = 0;  // near-coplanar lights or zero solution
  double seconds = 0;                          // wall time of the solve
  std::string message;                         // one human-readable line

  nlohmann::json to_json() const;
};

struct SolveResult {
  cv::Mat normals;   // CV_32FC3 (x, y, z), unit where solved, zero elsewhere
  cv::Mat albedo;    // CV_32FC1, zero where not solved
  cv::Mat residual;  // CV_32FC1, RMS of the fit over the observations used, zero where not solved
  cv::Mat solved;    // CV_8UC1, 255 where solved
  // Optional per-pixel outputs (empty when a method does not produce them):
  cv::Mat confidence;                    // CV_32FC1 in [0, 1], 1 = the data fit the method's model well
  cv::Mat coefficients;                  // CV_32FC(k), a per-pixel reflectance model (see `reflectance`)
  nlohmann::json reflectance = nullptr;  // describes `coefficients` (model, order, term order)
  nlohmann::json parameters = nlohmann::json::object();  // the options used, for summary.json
  SolveSummary summary;
};

}  // namespace lightstage
