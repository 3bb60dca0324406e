#include "lightstage/host/solvers/robust.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/select_kth.hpp"
#include "solvers/lambert_fit.hpp"
#include "solvers/pixel_driver.hpp"

#include <fmt/format.h>
#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <random>

namespace lightstage {

const char* robust_estimator_name(RobustEstimator estimator) {
  switch (estimator) {
    case RobustEstimator::kNone:
      return "none";
    case RobustEstimator::kIrlsL1:
      return "irls-l1";
    case RobustEstimator::kRansac:
      return "ransac";
  }
  return "?";
}

RobustEstimator parse_robust_estimator(const std::string& text) {
  if (text == "none") return RobustEstimator::kNone;
  if (text == "irls-l1") return RobustEstimator::kIrlsL1;
  if (text == "ransac") return RobustEstimator::kRansac;
  fail("--estimator: unknown robust estimator '{}' (none, irls-l1, ransac)", text);
}

void RobustOptions::check() const {
  detail::check_shadow_threshold("RobustOptions", shadow_threshold);
  if (!(t_low > 0 && t_low <= 1)) fail("RobustOptions.t_low (--t-low): must be in (0, 1], got {}", t_low);
  if (!(inlier_sigmas >= 0 && std::isfinite(inlier_sigmas)))
    fail("RobustOptions.inlier_sigmas: must be 0 (off) or positive, got {}", inlier_sigmas);
  if (irls_iterations < 1) fail("RobustOptions.irls_iterations: must be at least 1, got {}", irls_iterations);
  if (!(irls_epsilon > 0 && std::isfinite(irls_epsilon)))
    fail("RobustOptions.irls_epsilon: must be positive, got {}", irls_epsilon);
  if (ransac_iterations < 1)
    fail("RobustOptions.ransac_iterations: must be at least 1, got {}", ransac_iterations);
  if (!(ransac_threshold > 0 && std::isfinite(ransac_threshold)))
    fail("RobustOptions.ransac_threshold: must be positive, got {}", ransac_threshold);
  detail::check_min_observations("RobustOptions", min_observations);
  detail::check_threads("RobustOptions", threads);
}

nlohmann::json RobustOptions::to_json() const {
  return {{"shadow_threshold", shadow_threshold},
          {"t_low", t_low},
          {"estimator", robust_estimator_name(estimator)},
          {"inlier_sigmas", inlier_sigmas},
          {"irls_iterations", irls_iterations},
          {"irls_epsilon", irls_epsilon},
          {"ransac_iterations", ransac_iterations},
          {"ransac_threshold", ransac_threshold},
          {"seed", seed},
          {"min_observations", min_observations},
          {"screen_cast_shadows", screen_cast_shadows},
          {"drop_saturated", drop_saturated},
          {"threads", threads}};
}

namespace {

// RANSAC's refits on its inliers (locally optimised RANSAC).
constexpr int kRefitRounds = 4;
// RANSAC stops early once an all-inlier triple has been drawn with this probability.
constexpr double kConfidence = 0.999;
// The cast-shadow screen drops values under this fraction of the consensus
// prediction: far enough below that a broad specular lobe biasing the
// consensus upward does not drop the (darker) diffuse values T_low wants.
constexpr double kScreenRatio = 0.5;
// ... and the lights it puts within this many inlier bands of the terminator.
constexpr double kTerminator = 0.25;
// The fraction of the lit values the consensus must explain for the screen to act.
constexpr double kMinConsensus = 0.5;
// Inlier refit: the median absolute residual over σ for Gaussian noise.
constexpr double kMadToSigma = 1.4826;
// ... the values T_low dropped join when their median standardised residual
// is within this many of the selection's σ.
constexpr double kExpandRatio = 3;
// ... the noise model's floor: predictions below this share of the selection's
// median count as it (dark values are no more certain than this: read noise,
// quantisation, the penumbrae a threshold lets through).
constexpr double kNoiseFloorShare = 0.1;

// Usable and above the shadow threshold: what every step may fit.
bool is_lit(const PixelObservations& pixel, Eigen::Index j, const RobustOptions& options) {
  return pixel.usable[static_cast<std::size_t>(j)] && pixel.values(j) > options.shadow_threshold;
}

// The median of `values` (reordered; not empty).
double median_in_place(std::vector<double>& values) {
  const auto size = static_cast<std::ptrdiff_t>(values.size());
  return select_kth(values.data(), size, size / 2);
}

double median_of(const PixelObservations& pixel, const std::vector<Eigen::Index>& kept,
                 std::vector<double>& scratch) {
  scratch.clear();
  for (const Eigen::Index j : kept) scratch.push_back(pixel.values(j));
  return median_in_place(scratch);
}

bool irls_l1(const PixelObservations& pixel, const RobustOptions& options, double scale, RobustWorkspace& ws,
             Eigen::Vector3d& s) {
  const double epsilon = options.irls_epsilon * scale;
  ws.weights.setZero(pixel.count());
  for (int it = 0; it < options.irls_iterations; ++it) {
    for (const Eigen::Index j : ws.kept)
      ws.weights(j) = 1.0 / std::max(std::abs(pixel.lights.row(j).dot(s) - pixel.values(j)), epsilon);
    Eigen::Vector3d next;
    if (!detail::lambert_fit(pixel.lights, pixel.values, ws.kept, next, &ws.weights)) return true;
    const double change = (next - s).norm();
    s = next;
    if (change < 1e-9 * std::max(s.norm(), 1e-12)) break;
  }
  return true;
}

bool ransac(const PixelObservations& pixel, const RobustOptions& options, std::size_t pixel_index,
            double band, RobustWorkspace& ws, Eigen::Vector3d& s) {
  std::mt19937_64 rng(options.seed * 0x9E3779B97F4A7C15ULL + pixel_index);
  const std::size_t m = ws.kept.size();
  std::uniform_int_distribution<std::size_t> pick(0, m - 1);
  std::size_t best_count = 0;
  double best_error = 0;
  Eigen::Vector3d best = s;
  for (int it = 0; it < options.ransac_iterations; ++it) {
    const std::size_t a = pick(rng), b = pick(rng), c = pick(rng);
    if (a == b || b == c || a == c) continue;
    Eigen::Matrix3d l;
    l.row(0) = pixel.lights.row(ws.kept[a]);
    l.row(1) = pixel.lights.row(ws.kept[b]);
    l.row(2) = pixel.lights.row(ws.kept[c]);
    if (std::abs(l.determinant()) < 1e-6) continue;
    const Eigen::Vector3d candidate = l.partialPivLu().solve(
        Eigen::Vector3d(pixel.values(ws.kept[a]), pixel.values(ws.kept[b]), pixel.values(ws.kept[c])));
    if (candidate.z() <= 0) continue;  // a visible surface faces the camera
    std::size_t count = 0;
    double error = 0;
    for (const Eigen::Index j : ws.kept) {
      const double r = std::abs(pixel.lights.row(j).dot(candidate) - pixel.values(j));
      if (r < band) {
        ++count;
        error += r;
      }
    }
    if (count > best_count || (count == best_count && error < best_error)) {
      best_count = count;
      best_error = error;
      best = candidate;
      // Adaptive stop (Fischler–Bolles): enough triples that an all-inlier
      // one was drawn with probability kConfidence at the inlier ratio seen.
      const double ratio = static_cast<double>(best_count) / static_cast<double>(m);
      const double miss = 1 - ratio * ratio * ratio;
      if (miss <= 0 || it + 1 >= std::log(1 - kConfidence) / std::log(miss)) break;
    }
  }
  if (best_count < 3) return true;  // keep the least-squares start
  // Local optimisation: least squares on the inliers, whose set is then taken
  // again from the refit (a few rounds; the triple's own solution is noisy).
  s = best;
  std::size_t previous = 0;
  for (int round = 0; round < kRefitRounds; ++round) {
    ws.inliers.clear();
    for (const Eigen::Index j : ws.kept) {
      if (std::abs(pixel.lights.row(j).dot(s) - pixel.values(j)) < band) ws.inliers.push_back(j);
    }
    if (ws.inliers.size() < 3 || ws.inliers.size() == previous) break;
    previous = ws.inliers.size();
    Eigen::Vector3d refit;
    if (!detail::lambert_fit(pixel.lights, pixel.values, ws.inliers, refit)) break;
    s = refit;
  }
  return true;
}

// The estimator found the outliers; least squares is the efficient fit to
// the rest. Every observation the robust fit explains to within
// inlier_sigmas noise deviations (σ from the selection's residuals, scaled by
// the noise model) is refitted by weighted least squares (weights 1/σ²). The
// values T_low dropped join when the fit explains them about as well as the
// selection (a Lambertian pixel: twice the data); where they stray (a broad
// lobe), only the selection is refitted.
//
// The noise model: with distant lights σ grows as shot noise does, as the
// square root of the predicted value (above the floor). With near lights the
// surface point is a guess (a plane), so the light directions are off most at
// grazing light, where values are darkest: that error does not shrink with
// the signal, and σ is constant.
void refit_inliers(const PixelObservations& pixel, const RobustOptions& options, double scale,
                   RobustWorkspace& ws, Eigen::Vector3d& s) {
  const double floor = kNoiseFloorShare * scale;
  const bool shot_noise = !pixel.near_lights();
  auto deviation = [&](Eigen::Index j) {  // relative to the scale's
    return shot_noise ? std::sqrt(std::max(pixel.lights.row(j).dot(s), floor) / scale) : 1.0;
  };
  auto standardised = [&](Eigen::Index j) {
    return std::abs(pixel.lights.row(j).dot(s) - pixel.values(j)) / deviation(j);
  };
  ws.scratch.clear();
  for (const Eigen::Index j : ws.kept) ws.scratch.push_back(standardised(j));
  const double sigma = kMadToSigma * median_in_place(ws.scratch);
  if (!(sigma > 0)) return;

  ws.in_selection.assign(static_cast<std::size_t>(pixel.count()), 0);
  for (const Eigen::Index j : ws.kept) ws.in_selection[static_cast<std::size_t>(j)] = 1;
  auto lit = [&](Eigen::Index j) { return is_lit(pixel, j, options); };
  ws.scratch.clear();
  for (Eigen::Index j = 0; j < pixel.count(); ++j) {
    if (lit(j) && !ws.in_selection[static_cast<std::size_t>(j)]) ws.scratch.push_back(standardised(j));
  }
  const bool expand = ws.scratch.empty() || kMadToSigma * median_in_place(ws.scratch) <= kExpandRatio * sigma;

  const double band = options.inlier_sigmas * sigma;
  std::size_t previous = 0;
  for (int round = 0; round < kRefitRounds; ++round) {
    ws.inliers.clear();
    ws.weights.setZero(pixel.count());
    for (Eigen::Index j = 0; j < pixel.count(); ++j) {
      if (!lit(j) || (!expand && !ws.in_selection[static_cast<std::size_t>(j)])) continue;
      const double d = deviation(j);
      if (std::abs(pixel.lights.row(j).dot(s) - pixel.values(j)) < band * d) {
        ws.inliers.push_back(j);
        ws.weights(j) = 1 / (d * d);
      }
    }
    if (static_cast<int>(ws.inliers.size()) < options.min_observations || ws.inliers.size() == previous)
      break;
    previous = ws.inliers.size();
    Eigen::Vector3d refit;
    if (!detail::lambert_fit(pixel.lights, pixel.values, ws.inliers, refit, &ws.weights)) break;
    s = refit;
  }
}

}  // namespace

RobustPixelFit fit_robust_pixel(const PixelObservations& pixel, const RobustOptions& options,
                                std::size_t pixel_index, RobustWorkspace& ws) {
  RobustPixelFit fit;
  ws.kept.clear();
  for (Eigen::Index j = 0; j < pixel.count(); ++j) {
    if (is_lit(pixel, j, options)) ws.kept.push_back(j);
  }
  // Cast-shadow screen: a consensus fit over every lit observation; values
  // well below it are light the surface did not get (cast shadows and their
  // penumbrae, which the darkest-T_low selection below would otherwise prefer).
  if (options.screen_cast_shadows && ws.kept.size() > 3) {
    Eigen::Vector3d consensus;
    if (detail::lambert_fit(pixel.lights, pixel.values, ws.kept, consensus)) {
      const double band = options.ransac_threshold * std::max(median_of(pixel, ws.kept, ws.scratch), 1e-12);
      ws.inliers.clear();
      ransac(pixel, options, pixel_index, band, ws, consensus);
      // Only a consensus most lit values agree with (a Lambertian pixel with
      // sparse outliers) is trusted; a broad lobe biases it instead.
      if (static_cast<double>(ws.inliers.size()) >= kMinConsensus * static_cast<double>(ws.kept.size()))
        // Also the lights the fit puts at the terminator: there dark noise and
        // penumbrae are all a value can hold, and T_low would prefer them.
        std::erase_if(ws.kept, [&](Eigen::Index j) {
          const double predicted = pixel.lights.row(j).dot(consensus);
          return pixel.values(j) < kScreenRatio * predicted - band || predicted < kTerminator * band;
        });
    }
  }
  if (options.t_low < 1.0) {
    std::stable_sort(ws.kept.begin(), ws.kept.end(),
                     [&](Eigen::Index a, Eigen::Index b) { return pixel.values(a) < pixel.values(b); });
    const auto keep = std::max<std::size_t>(
        static_cast<std::size_t>(options.min_observations),
        static_cast<std::size_t>(std::ceil(options.t_low * static_cast<double>(ws.kept.size()) - 1e-9)));
    ws.kept.resize(std::min(keep, ws.kept.size()));
  }
  if (static_cast<int>(ws.kept.size()) < options.min_observations) {
    fit.status = RobustPixelFit::Status::kTooFewObservations;
    return fit;
  }
  Eigen::Vector3d s;
  if (!detail::lambert_fit(pixel.lights, pixel.values, ws.kept, s)) return fit;
  const double scale = std::max(median_of(pixel, ws.kept, ws.scratch), 1e-12);
  const double band = options.ransac_threshold * scale;
  switch (options.estimator) {
    case RobustEstimator::kNone:
      break;
    case RobustEstimator::kIrlsL1:
      irls_l1(pixel, options, scale, ws, s);
      break;
    case RobustEstimator::kRansac:
      if (ws.kept.size() > 3) ransac(pixel, options, pixel_index, band, ws, s);
      break;
  }
  if (!s.allFinite() || s.norm() < 1e-12) return fit;
  if (options.inlier_sigmas > 0) refit_inliers(pixel, options, scale, ws, s);
  double squared = 0;
  std::size_t inside = 0;
  for (const Eigen::Index j : ws.kept) {
    const double r = pixel.lights.row(j).dot(s) - pixel.values(j);
    squared += r * r;
    if (std::abs(r) < band) ++inside;
  }
  fit.status = RobustPixelFit::Status::kSolved;
  fit.s = s;
  fit.rms = std::sqrt(squared / static_cast<double>(ws.kept.size()));
  fit.inlier_fraction = static_cast<double>(inside) / static_cast<double>(ws.kept.size());
  return fit;
}

SolveResult solve_robust(const Observations& observations, const RobustOptions& options) {
  options.check();
  const detail::DriverSettings settings = detail::driver_settings("robust", options);
  SolveResult result;
  detail::run_per_pixel(
      observations, settings,
      [&options, &observations]() -> detail::PixelCore {
        auto ws = std::make_shared<RobustWorkspace>();
        return [ws, &options, &observations](const PixelObservations& pixel, std::size_t p,
                                             detail::PixelOutcome& out) {
          // The seed follows the pixel's place in the whole image, so a band draws what the whole image
          // would.
          const RobustPixelFit fit = fit_robust_pixel(pixel, options, observations.first_pixel + p, *ws);
          if (fit.status == RobustPixelFit::Status::kTooFewObservations) {
            out.status = detail::PixelOutcome::Status::kTooFewObservations;
            return;
          }
          if (fit.status != RobustPixelFit::Status::kSolved) return;
          out.status = detail::PixelOutcome::Status::kSolved;
          out.normal = fit.s;
          out.albedo = fit.s.norm();
          out.residual = fit.rms;
        };
      },
      result);
  result.parameters = options.to_json();
  SolveSummary& s = result.summary;
  const std::string estimator = robust_estimator_name(options.estimator);
  s.settings = {{"estimator", estimator, estimator},
                {"t_low", options.t_low, fmt::format("T_low {:.0f}%", 100 * options.t_low)}};
  s.message = s.format_message();
  return result;
}

}  // namespace lightstage
