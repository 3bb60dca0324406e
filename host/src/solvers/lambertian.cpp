#include "lightstage/host/solvers/lambertian.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/parallel.hpp"
#include "lightstage/common/simd_clones.hpp"
#include "lightstage/host/solvers/normal_confidence.hpp"
#include "lightstage/host/solvers/pixel_observations.hpp"
#include "solvers/confidence_lanes.hpp"
#include "solvers/pixel_driver.hpp"
#include "solvers/pixel_lanes.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <vector>

namespace lightstage {
namespace {

// Smallest / largest eigenvalue of LᵀL below which the lights count as coplanar
// (a condition number of L above 1000).
constexpr double kMinEigenvalueRatio = 1e-6;

struct Counters {
  std::size_t solved = 0;
  std::size_t too_few = 0;
  std::size_t degenerate = 0;
};

struct Maps {
  cv::Mat normals, albedo, residual, solved;
  cv::Mat predicted_error;  // with L2Options::confidence
};

// Stores s for one pixel; false (degenerate) when s is zero or not finite.
bool store(const Eigen::Vector3d& s, double rms, const cv::Point& pixel, Maps& maps) {
  const double length = s.norm();
  if (!std::isfinite(length) || length < 1e-12) return false;
  const Eigen::Vector3d n = s / length;
  maps.normals.at<cv::Vec3f>(pixel) =
      cv::Vec3f(static_cast<float>(n.x()), static_cast<float>(n.y()), static_cast<float>(n.z()));
  maps.albedo.at<float>(pixel) = static_cast<float>(length);
  maps.residual.at<float>(pixel) = static_cast<float>(rms);
  maps.solved.at<std::uint8_t>(pixel) = 255;
  return true;
}

// All observations: one pseudo-inverse for every pixel.
Counters solve_all(const Observations& obs, const L2Options& options, Maps& maps) {
  const Eigen::Index images = static_cast<Eigen::Index>(obs.image_count());
  const std::size_t pixels = obs.pixel_count();
  Counters total;
  if (images < options.min_observations) {
    total.too_few = pixels;
    if (options.progress) options.progress(pixels);
    return total;
  }
  const Eigen::MatrixX3d& lights = obs.lights;
  const Eigen::Matrix3d gram = lights.transpose() * lights;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(gram);
  const Eigen::Vector3d lambda = eigen.eigenvalues();
  if (!(lambda(0) > kMinEigenvalueRatio * lambda(2))) {
    total.degenerate = pixels;
    if (options.progress) options.progress(pixels);
    return total;
  }
  const Eigen::Matrix<double, 3, Eigen::Dynamic> pinv = gram.inverse() * lights.transpose();
  // Resolved once: the chunks must be no more than the counters made for them.
  const int threads = resolve_threads(options.threads);
  std::vector<Counters> per_chunk(static_cast<std::size_t>(threads));
  // Blocks of pixels as matrix products (S = I·P, as GEMM): the stack is read
  // once, from cache, instead of as one small product per pixel. The residual
  // needs no second pass: with s the least-squares solution,
  // |I − L s|² = |I|² − sᵀ(LᵀL)s.
  const Eigen::Matrix<double, Eigen::Dynamic, 3> pinv_t = pinv.transpose();
  parallel_chunks(pixels, threads, [&](std::size_t chunk, std::size_t begin, std::size_t end) {
    Counters& counters = per_chunk[chunk];
    constexpr std::size_t kBlock = 64;
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> values(kBlock, images);
    Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> solutions(kBlock, 3);
    detail::ProgressBatch batch(options.progress);
    for (std::size_t first = begin; first < end; first += kBlock) {
      const auto rows = static_cast<Eigen::Index>(std::min(kBlock, end - first));
      values.topRows(rows) =
          obs.intensities.middleRows(static_cast<Eigen::Index>(first), rows).template cast<double>();
      solutions.topRows(rows).noalias() = values.topRows(rows) * pinv_t;
      for (Eigen::Index k = 0; k < rows; ++k) {
        batch.tick();
        const Eigen::Vector3d s = solutions.row(k).transpose();
        const double squared = std::max(0.0, values.row(k).squaredNorm() - s.dot(gram * s));
        if (store(s, std::sqrt(squared / static_cast<double>(images)),
                  obs.pixels[first + static_cast<std::size_t>(k)], maps)) {
          ++counters.solved;
        } else {
          ++counters.degenerate;
        }
      }
    }
  });
  for (const auto& c : per_chunk) {
    total.solved += c.solved;
    total.degenerate += c.degenerate;
  }
  return total;
}

// Each light's weight (1 kept, 0 not: finite and above the threshold) and
// value at unit light (the observed float divided by the near light's gain
// as a float); per lane the kept lights.
LIGHTSTAGE_SIMD_CLONES void kept_values(const LightLanes& lanes, double shadow_threshold, PixelLanes* weight,
                                        PixelLanes* corrected, PixelLanes& kept_count) {
  using FloatLanes = float __attribute__((vector_size(kPixelLanes * sizeof(float))));
  const PixelLanes zero = {}, one = PixelLanes{} + 1.0;
  const bool threshold = shadow_threshold >= 0;
  PixelLanes count = {};
  for (std::size_t j = 0; j < lanes.images(); ++j) {
    const PixelLanes value = lanes.observed[j];
    PixelMask keep = value - value == zero;  // finite
    if (threshold) keep &= value > shadow_threshold;
    weight[j] = keep ? one : zero;
    count += weight[j];
    corrected[j] = lanes.near_lights()
                       ? __builtin_convertvector(__builtin_convertvector(value, FloatLanes) /
                                                     __builtin_convertvector(lanes.gain[j], FloatLanes),
                                                 PixelLanes)
                       : value;
  }
  kept_count = count;
}

// The normal equations over the lights of weight 1.
LIGHTSTAGE_SIMD_CLONES void normal_equations(const LightLanes& lanes, const PixelLanes* weight,
                                             const PixelLanes* values, NormalEquationLanes& sums) {
  NormalEquationLanes local;  // in registers: the arrays could alias the caller's
  const PixelLanes zero = {};
  for_each_light_in_two_sets(
      lanes.images(), [&](int set, std::size_t j) __attribute__((always_inline)) {
        local.add(set, weight[j] != zero, lanes.x[j], lanes.y[j], lanes.z[j], values[j]);
      });
  sums = local;
}

// Σ (lᵀs − v)² over the lights of weight 1: the even and the odd lights'
// sums added, then the last of an odd count (after, not in the even set: as
// the light pairs' sum was).
LIGHTSTAGE_SIMD_CLONES void squared_residual(const LightLanes& lanes, const PixelLanes* weight,
                                             const PixelLanes* values, const PixelLanes& sx,
                                             const PixelLanes& sy, const PixelLanes& sz,
                                             PixelLanes& squared) {
  const PixelLanes zero = {};
  PixelLanes r;
  const auto residual = [&](std::size_t j) __attribute__((always_inline)) {
    const PixelLanes fitted = lanes.x[j] * sx + lanes.y[j] * sy + lanes.z[j] * sz;
    r = weight[j] != zero ? fitted - values[j] : zero;
  };
  PixelLanes even = {}, odd = {};
  const std::size_t images = lanes.images();
  std::size_t j = 0;
  for (; j + 2 <= images; j += 2) {
    residual(j);
    even += r * r;
    residual(j + 1);
    odd += r * r;
  }
  squared = even + odd;
  if (j < images) {
    residual(j);
    squared += r * r;
  }
}

// Keeps only the darkest ceil(t_low · kept) of lane `lane`'s kept lights
// (ties in light order); returns how many.
std::size_t keep_darkest(std::size_t lane, double t_low, std::size_t images, const PixelLanes* corrected,
                         PixelLanes* weight, std::vector<std::size_t>& kept) {
  kept.clear();
  for (std::size_t j = 0; j < images; ++j)
    if (weight[j][lane] != 0) kept.push_back(j);
  const auto keep = static_cast<std::size_t>(std::ceil(t_low * static_cast<double>(kept.size()) - 1e-9));
  std::stable_sort(kept.begin(), kept.end(),
                   [&](std::size_t a, std::size_t b) { return corrected[a][lane] < corrected[b][lane]; });
  for (std::size_t k = std::min(keep, kept.size()); k < kept.size(); ++k) weight[kept[k]][lane] = 0.0;
  return std::min(keep, kept.size());
}

// Per-pixel selection: shadows dropped, the lowest t_low kept, 3×3 normal
// equations, kPixelLanes pixels at a time (pixel_lanes.hpp). With near
// lights each pixel has its own light directions, and its values are divided
// by the falloff gains before the fit (the shadow threshold still applies to
// the observed values).
// With L2Options::confidence each solved pixel's error is predicted while its
// lights are at hand (a near light's direction is the costliest part of both),
// at the normal predict_normal_error would judge after the solve's clamp (on
// the horizon where it faced away, clamp_facing_away).
Counters solve_selected(const Observations& obs, const L2Options& options, Maps& maps) {
  const auto images = static_cast<std::size_t>(obs.image_count());
  const std::size_t pixels = obs.pixel_count();
  const Eigen::VectorXd reference = obs.near ? near_light_reference(*obs.near) : Eigen::VectorXd();
  // Resolved once: the chunks must be no more than the counters made for them.
  const int threads = resolve_threads(options.threads);
  std::vector<Counters> per_chunk(static_cast<std::size_t>(threads));
  parallel_chunks(pixels, threads, [&](std::size_t chunk, std::size_t begin, std::size_t end) {
    Counters& counters = per_chunk[chunk];
    LightLanes lanes;
    std::optional<ConfidenceLanes> predictor;
    if (options.confidence) predictor.emplace(*options.confidence);
    LaneBuffer weight, corrected;
    weight.resize(images);
    corrected.resize(images);
    std::vector<std::size_t> kept;
    kept.reserve(images);
    detail::ProgressBatch batch(options.progress);
    for (std::size_t first = begin; first < end; first += kPixelLanes) {
      const std::size_t count = std::min(kPixelLanes, end - first);
      std::size_t group[kPixelLanes];
      for (std::size_t lane = 0; lane < count; ++lane) {
        group[lane] = first + lane;
        batch.tick();
      }
      load_light_lanes(obs, reference, group, count, lanes);
      PixelLanes kept_count;
      kept_values(lanes, options.shadow_threshold, weight.data(), corrected.data(), kept_count);
      std::size_t used[kPixelLanes];
      for (std::size_t lane = 0; lane < count; ++lane)
        used[lane] = options.t_low < 1.0
                         ? keep_darkest(lane, options.t_low, images, corrected.data(), weight.data(), kept)
                         : static_cast<std::size_t>(kept_count[lane]);
      NormalEquationLanes sums;
      normal_equations(lanes, weight.data(), corrected.data(), sums);
      Eigen::Vector3d s[kPixelLanes];
      bool solvable[kPixelLanes] = {};
      PixelLanes sx = {}, sy = {}, sz = {};
      for (std::size_t lane = 0; lane < count; ++lane) {
        if (static_cast<int>(used[lane]) < options.min_observations) {
          ++counters.too_few;
          continue;
        }
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
        eigen.computeDirect(sums.gram_matrix(lane));
        const Eigen::Vector3d lambda = eigen.eigenvalues();
        if (!(lambda(0) > kMinEigenvalueRatio * lambda(2))) {
          ++counters.degenerate;
          continue;
        }
        const Eigen::Matrix3d& v = eigen.eigenvectors();
        s[lane] = v * (v.transpose() * sums.moment_vector(lane)).cwiseQuotient(lambda);
        sx[lane] = s[lane].x();
        sy[lane] = s[lane].y();
        sz[lane] = s[lane].z();
        solvable[lane] = true;
      }
      PixelLanes squared;
      squared_residual(lanes, weight.data(), corrected.data(), sx, sy, sz, squared);
      bool judged[kPixelLanes] = {};
      Eigen::Vector3d normals[kPixelLanes];
      double albedo[kPixelLanes], errors[kPixelLanes];
      for (std::size_t lane = 0; lane < count; ++lane) {
        if (!solvable[lane]) continue;
        const cv::Point at = obs.pixels[group[lane]];
        if (!store(s[lane], std::sqrt(squared[lane] / static_cast<double>(used[lane])), at, maps)) {
          ++counters.degenerate;
          continue;
        }
        ++counters.solved;
        if (!predictor) continue;
        cv::Vec3f stored = maps.normals.at<cv::Vec3f>(at);
        if (stored[2] < 0) stored = on_horizon(stored);
        // A stored normal not judged keeps the map's 0, as the separate pass leaves it.
        judged[lane] = judged_normal(stored, normals[lane]);
        albedo[lane] = maps.albedo.at<float>(at);
      }
      if (!predictor || std::none_of(judged, judged + count, [](bool j) { return j; })) continue;
      predictor->predict(lanes, normals, albedo, judged, errors);
      for (std::size_t lane = 0; lane < count; ++lane)
        if (judged[lane])
          maps.predicted_error.at<float>(obs.pixels[group[lane]]) = static_cast<float>(errors[lane]);
    }
  });
  Counters total;
  for (const auto& c : per_chunk) {
    total.solved += c.solved;
    total.too_few += c.too_few;
    total.degenerate += c.degenerate;
  }
  return total;
}

}  // namespace

void L2Options::check() const {
  if (!std::isfinite(shadow_threshold))
    fail("L2Options.shadow_threshold: must be finite, got {}", shadow_threshold);
  if (!(t_low > 0 && t_low <= 1)) fail("L2Options.t_low: must be in (0, 1], got {}", t_low);
  if (min_observations < 3) fail("L2Options.min_observations: must be at least 3, got {}", min_observations);
  if (threads < 0) fail("L2Options.threads: must be 0 (automatic) or positive, got {}", threads);
}

nlohmann::json L2Options::to_json() const {
  return {{"shadow_threshold", shadow_threshold},
          {"t_low", t_low},
          {"min_observations", min_observations},
          {"threads", threads}};
}

SolveResult solve_lambertian(const Observations& observations, const L2Options& options) {
  options.check();
  const auto start = std::chrono::steady_clock::now();
  const cv::Size size = observations.size;
  // The matrices' sizes, the saturation flags the lanes read and the near lights' tables.
  check_observations(observations, "solve_lambertian");
  Maps maps{cv::Mat(size, CV_32FC3, cv::Scalar::all(0)), cv::Mat(size, CV_32FC1, cv::Scalar::all(0)),
            cv::Mat(size, CV_32FC1, cv::Scalar::all(0)), cv::Mat(size, CV_8UC1, cv::Scalar::all(0)),
            cv::Mat()};
  if (options.confidence) options.confidence->check();
  // Near lights: every pixel has its own lights, so no shared pseudo-inverse.
  const bool all = options.shadow_threshold < 0 && options.t_low >= 1.0 && !observations.near;
  if (options.confidence && !all) maps.predicted_error = cv::Mat(size, CV_32FC1, cv::Scalar::all(0));
  const Counters counters =
      all ? solve_all(observations, options, maps) : solve_selected(observations, options, maps);

  SolveResult result;
  result.normals = maps.normals;
  result.albedo = maps.albedo;
  result.residual = maps.residual;
  result.solved = maps.solved;
  result.predicted_error = maps.predicted_error;
  result.parameters = options.to_json();
  SolveSummary& summary = result.summary;
  summary.method = "l2";
  summary.pixels_in_mask = observations.pixel_count();
  summary.pixels_solved = counters.solved;
  summary.pixels_rejected_too_few_observations = counters.too_few;
  summary.pixels_rejected_degenerate = counters.degenerate;
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  summary.settings = {all                 ? SolveFact{"mode", "all", "all observations, one pseudo-inverse"}
                      : observations.near ? SolveFact{"mode", "near", "per-pixel near lights"}
                                          : SolveFact{"mode", "selected", "per-pixel selection"}};
  summary.message = summary.format_message();
  return result;
}

}  // namespace lightstage
