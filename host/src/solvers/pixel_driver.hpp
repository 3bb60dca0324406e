#pragma once
// The loop every per-pixel method shares: load each pixel's observations
// (per-pixel lights when near lights are set), run the method's core on a
// worker thread, write the maps and count what was solved or rejected.

#include "lightstage/host/solvers/pixel_observations.hpp"
#include "lightstage/host/solvers/solve_result.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace lightstage::detail {

struct PixelOutcome {
  enum class Status { kSolved, kTooFewObservations, kDegenerate };
  Status status = Status::kDegenerate;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  double albedo = 0;
  double residual = 0;           // RMS over the observations the method used
  Eigen::VectorXd coefficients;  // size = coefficient_count of the run
  int iterations = 0;
  std::uint8_t choice = 0;  // 1-based index into DriverSettings::choices (methods that choose)
};

// A core solves one pixel; each worker thread gets its own (own workspace).
using PixelCore = std::function<void(const PixelObservations&, std::size_t pixel, PixelOutcome&)>;

// Counts one worker's pixels and hands them to a SolveProgress in batches (and
// the rest when it goes out of scope), so workers rarely touch shared state.
// A progress that throws (a solve stopped by its caller) ends the worker's
// loop at tick(); the last report, from the destructor, is never thrown.
class ProgressBatch {
 public:
  explicit ProgressBatch(const SolveProgress& progress) : progress_(progress) {}
  ~ProgressBatch() {
    try {
      flush();
    } catch (...) {  // NOLINT(bugprone-empty-catch): the stop is seen at the caller's next step
    }
  }
  ProgressBatch(const ProgressBatch&) = delete;
  ProgressBatch& operator=(const ProgressBatch&) = delete;
  void tick() {
    if (progress_ && ++pending_ == kBatch) flush();
  }
  void flush() {
    const std::size_t done = std::exchange(pending_, 0);
    if (progress_ && done > 0) progress_(done);
  }

 private:
  static constexpr std::size_t kBatch = 256;
  const SolveProgress& progress_;
  std::size_t pending_ = 0;
};

struct DriverSettings {
  std::string method;                // summary.method
  int threads = 0;                   // 0 = hardware concurrency
  bool drop_saturated = true;        // passed to load_pixel
  int coefficient_count = 0;         // > 0: a CV_32FC(k) coefficient map is written
  std::vector<std::string> choices;  // non-empty: a choice map is written (SolveResult::choice)
  SolveProgress progress;            // pixels done; empty = none
};

// The settings a method's options carry for the driver: threads, progress and
// drop_saturated (every per-pixel method's options have them).
template <typename Options>
DriverSettings driver_settings(std::string method, const Options& options) {
  DriverSettings settings;
  settings.method = std::move(method);
  settings.threads = options.threads;
  settings.progress = options.progress;
  settings.drop_saturated = options.drop_saturated;
  return settings;
}

// The option checks per-pixel methods share; each throws InputError naming
// `owner` (the options struct, "RobustOptions"), the field and its flag.
void check_shadow_threshold(const char* owner, double shadow_threshold);  // finite and >= 0
void check_min_observations(const char* owner, int min_observations);     // at least 3
void check_threads(const char* owner, int threads);                       // 0 (automatic) or positive

// Runs `make_core()` once per worker and the core once per pixel. Fills every
// map of the result (normals, albedo, residual, solved and, when asked,
// coefficients and the choice map) and the summary counts; the caller adds parameters,
// reflectance, the summary's settings and findings, and its message. Returns
// the mean iterations over solved pixels.
double run_per_pixel(const Observations& observations, const DriverSettings& settings,
                     const std::function<PixelCore()>& make_core, SolveResult& result);

// Zeroed normal, albedo, residual and solved maps of `size` in `result`.
void allocate_result_maps(cv::Size size, SolveResult& result);

}  // namespace lightstage::detail
