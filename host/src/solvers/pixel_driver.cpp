#include "solvers/pixel_driver.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/parallel.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

namespace lightstage::detail {
namespace {

struct Counters {
  std::size_t solved = 0, too_few = 0, degenerate = 0;
  double iterations = 0;
};

}  // namespace

void check_shadow_threshold(const char* owner, double shadow_threshold) {
  if (!(std::isfinite(shadow_threshold) && shadow_threshold >= 0))
    fail("{}.shadow_threshold (--shadow-threshold): must be finite and >= 0, got {}", owner,
         shadow_threshold);
}

void check_min_observations(const char* owner, int min_observations) {
  if (min_observations < 3)
    fail("{}.min_observations (--min-observations): must be at least 3, got {}", owner, min_observations);
}

void check_threads(const char* owner, int threads) {
  if (threads < 0) fail("{}.threads (--threads): must be 0 (automatic) or positive, got {}", owner, threads);
}

void allocate_result_maps(cv::Size size, SolveResult& result) {
  result.normals = cv::Mat(size, CV_32FC3, cv::Scalar::all(0));
  result.albedo = cv::Mat(size, CV_32FC1, cv::Scalar::all(0));
  result.residual = cv::Mat(size, CV_32FC1, cv::Scalar::all(0));
  result.solved = cv::Mat(size, CV_8UC1, cv::Scalar::all(0));
}

double run_per_pixel(const Observations& observations, const DriverSettings& settings,
                     const std::function<PixelCore()>& make_core, SolveResult& result) {
  const auto start = std::chrono::steady_clock::now();
  check_observations(observations, settings.method.c_str());
  const cv::Size size = observations.size;
  allocate_result_maps(size, result);
  const int k = settings.coefficient_count;
  if (k > 0) result.coefficients = cv::Mat(size, CV_32FC(k), cv::Scalar::all(0));
  if (!settings.choices.empty()) {
    if (settings.choices.size() > 255)
      fail("{}: at most 255 choices, got {}", settings.method, settings.choices.size());
    result.choice = cv::Mat(size, CV_8UC1, cv::Scalar::all(0));
    result.choices = settings.choices;
  }

  const std::size_t pixels = observations.pixel_count();
  // Resolved once: the chunks must be no more than the counters made for them.
  const int threads = resolve_threads(settings.threads);
  std::vector<Counters> per_chunk(static_cast<std::size_t>(threads));
  parallel_chunks(pixels, threads, [&](std::size_t chunk, std::size_t begin, std::size_t end) {
    Counters& counters = per_chunk[chunk];
    const PixelCore core = make_core();
    PixelObservations data;
    PixelOutcome outcome;
    ProgressBatch batch(settings.progress);
    for (std::size_t p = begin; p < end; ++p) {
      batch.tick();
      load_pixel(observations, p, settings.drop_saturated, data);
      outcome = PixelOutcome{};
      core(data, p, outcome);
      if (outcome.status == PixelOutcome::Status::kTooFewObservations) {
        ++counters.too_few;
        continue;
      }
      const double length = outcome.normal.norm();
      if (outcome.status != PixelOutcome::Status::kSolved || !std::isfinite(length) || length < 1e-12) {
        ++counters.degenerate;
        continue;
      }
      const Eigen::Vector3d n = outcome.normal / length;
      const cv::Point& at = observations.pixels[p];
      result.normals.at<cv::Vec3f>(at) =
          cv::Vec3f(static_cast<float>(n.x()), static_cast<float>(n.y()), static_cast<float>(n.z()));
      result.albedo.at<float>(at) = static_cast<float>(outcome.albedo);
      result.residual.at<float>(at) = static_cast<float>(outcome.residual);
      result.solved.at<std::uint8_t>(at) = 255;
      if (k > 0 && outcome.coefficients.size() == k) {
        auto* row = result.coefficients.ptr<float>(at.y) + static_cast<std::ptrdiff_t>(at.x) * k;
        for (int c = 0; c < k; ++c) row[c] = static_cast<float>(outcome.coefficients(c));
      }
      if (!result.choice.empty()) result.choice.at<std::uint8_t>(at) = outcome.choice;
      ++counters.solved;
      counters.iterations += outcome.iterations;
    }
  });
  Counters total;
  for (const auto& c : per_chunk) {
    total.solved += c.solved;
    total.too_few += c.too_few;
    total.degenerate += c.degenerate;
    total.iterations += c.iterations;
  }
  SolveSummary& summary = result.summary;
  summary.method = settings.method;
  summary.pixels_in_mask = pixels;
  summary.pixels_solved = total.solved;
  summary.pixels_rejected_too_few_observations = total.too_few;
  summary.pixels_rejected_degenerate = total.degenerate;
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return total.solved > 0 ? total.iterations / static_cast<double>(total.solved) : 0.0;
}

}  // namespace lightstage::detail
