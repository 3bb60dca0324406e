#include "lightstage/host/solvers/lambertian.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/parallel.hpp"
#include "lightstage/host/solvers/normal_confidence.hpp"
#include "lightstage/host/solvers/pixel_observations.hpp"
#include "solvers/normal_equation_pairs.hpp"
#include "solvers/pixel_driver.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
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

// The confidence's predicted error at the answer just stored for pixel `p`,
// at the normal predict_normal_error would judge after the solve's clamp
// (on the horizon where it faced away, clamp_facing_away). `data` holds the
// pixel's lights (and near gains) already.
float predicted_error(const Observations& obs, std::size_t p, const Maps& maps, PixelObservations& data,
                      PixelErrorPredictor& predictor) {
  const cv::Point at = obs.pixels[p];
  cv::Vec3f stored = maps.normals.at<cv::Vec3f>(at);
  if (stored[2] < 0) stored = on_horizon(stored);
  Eigen::Vector3d n;
  if (!judged_normal(stored, n)) return 0.f;
  load_pixel_values(obs, p, /*drop_saturated=*/true, data);
  return static_cast<float>(predictor.predict(data, n, maps.albedo.at<float>(at)));
}

// Per-pixel selection: shadows dropped, the lowest t_low kept, 3×3 normal equations.
// With near lights each pixel has its own light directions, and its values
// are divided by the falloff gains before the fit (the shadow threshold
// still applies to the observed values).
// With L2Options::confidence each solved pixel's error is predicted while its
// lights are at hand (a near light's direction is the costliest part of both).
Counters solve_selected(const Observations& obs, const L2Options& options, Maps& maps) {
  const Eigen::Index images = static_cast<Eigen::Index>(obs.image_count());
  const std::size_t pixels = obs.pixel_count();
  const Eigen::VectorXd centre_squared = obs.near ? near_light_reference(*obs.near) : Eigen::VectorXd();
  // Resolved once: the chunks must be no more than the counters made for them.
  const int threads = resolve_threads(options.threads);
  std::vector<Counters> per_chunk(static_cast<std::size_t>(threads));
  parallel_chunks(pixels, threads, [&](std::size_t chunk, std::size_t begin, std::size_t end) {
    Counters& counters = per_chunk[chunk];
    std::vector<Eigen::Index> kept;
    kept.reserve(static_cast<std::size_t>(images));
    PixelObservations data;  // the pixel's lights, and for the confidence its values
    if (!obs.near) data.lights = obs.lights;
    std::optional<PixelErrorPredictor> predictor;
    if (options.confidence) predictor.emplace(*options.confidence);
    Eigen::VectorXf corrected(images);
    std::vector<double> weight(static_cast<std::size_t>(images));  // 1 for a kept light, else 0
    detail::ProgressBatch batch(options.progress);
    for (std::size_t p = begin; p < end; ++p) {
      batch.tick();
      const auto observed = obs.intensities.row(static_cast<Eigen::Index>(p));
      corrected = observed.transpose();
      if (obs.near) {
        near_light_directions(*obs.near, centre_squared, p, data.lights, data.near_gains);
        corrected.array() /= data.near_gains.cast<float>().array();
      }
      const auto& row = corrected;
      std::size_t count = 0;
      for (Eigen::Index j = 0; j < images; ++j) {
        const float value = observed(j);
        const bool keep = std::isfinite(value) && !(options.shadow_threshold >= 0 &&
                                                    static_cast<double>(value) <= options.shadow_threshold);
        weight[static_cast<std::size_t>(j)] = keep ? 1.0 : 0.0;
        count += keep ? 1 : 0;
      }
      if (options.t_low < 1.0) {
        kept.clear();
        for (Eigen::Index j = 0; j < images; ++j)
          if (weight[static_cast<std::size_t>(j)] != 0) kept.push_back(j);
        const auto keep =
            static_cast<std::size_t>(std::ceil(options.t_low * static_cast<double>(kept.size()) - 1e-9));
        std::stable_sort(kept.begin(), kept.end(),
                         [&](Eigen::Index a, Eigen::Index b) { return row(a) < row(b); });
        for (std::size_t k = std::min(keep, kept.size()); k < kept.size(); ++k)
          weight[static_cast<std::size_t>(kept[k])] = 0.0;
        count = std::min(keep, kept.size());
      }
      if (static_cast<int>(count) < options.min_observations) {
        ++counters.too_few;
        continue;
      }
      // The normal equations, two lights at a time (a vector's lanes) over the
      // lights' columns; a light left out adds exact zeros (its value, maybe
      // not finite, is not read).
      const double* lx = data.lights.col(0).data();
      const double* ly = data.lights.col(1).data();
      const double* lz = data.lights.col(2).data();
      const float* values = row.data();
      NormalEquationPairs sums;
      const DoublePair zero = {};
      Eigen::Index j = 0;
      for (; j + 2 <= images; j += 2)
        sums.add(load_pair(weight.data() + j) != zero, load_pair(lx + j), load_pair(ly + j),
                 load_pair(lz + j), load_pair(values + j));
      if (j < images)  // the last light, in the first lane
        sums.add(DoublePair{weight[static_cast<std::size_t>(j)], 0.0} != zero, DoublePair{lx[j], 0.0},
                 DoublePair{ly[j], 0.0}, DoublePair{lz[j], 0.0},
                 DoublePair{static_cast<double>(values[j]), 0.0});
      const Eigen::Matrix3d gram = sums.gram_matrix();
      const Eigen::Vector3d rhs = sums.moment_vector();
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
      eigen.computeDirect(gram);
      const Eigen::Vector3d lambda = eigen.eigenvalues();
      if (!(lambda(0) > kMinEigenvalueRatio * lambda(2))) {
        ++counters.degenerate;
        continue;
      }
      const Eigen::Matrix3d& v = eigen.eigenvectors();
      const Eigen::Vector3d s = v * (v.transpose() * rhs).cwiseQuotient(lambda);
      const DoublePair sx = {s.x(), s.x()}, sy = {s.y(), s.y()}, sz = {s.z(), s.z()};
      DoublePair squares = {};
      for (j = 0; j + 2 <= images; j += 2) {
        const DoublePair fitted = load_pair(lx + j) * sx + load_pair(ly + j) * sy + load_pair(lz + j) * sz;
        const DoublePair r = load_pair(weight.data() + j) != zero ? fitted - load_pair(values + j) : zero;
        squares += r * r;
      }
      double squared = lane_sum(squares);
      if (j < images && weight[static_cast<std::size_t>(j)] != 0) {
        const double r = lx[j] * s.x() + ly[j] * s.y() + lz[j] * s.z() - static_cast<double>(values[j]);
        squared += r * r;
      }
      if (store(s, std::sqrt(squared / static_cast<double>(count)), obs.pixels[p], maps)) {
        ++counters.solved;
        if (predictor)
          maps.predicted_error.at<float>(obs.pixels[p]) = predicted_error(obs, p, maps, data, *predictor);
      } else {
        ++counters.degenerate;
      }
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
  if (static_cast<std::size_t>(observations.intensities.rows()) != observations.pixel_count() ||
      static_cast<std::size_t>(observations.intensities.cols()) != observations.image_count()) {
    fail("solve_lambertian: observations are {}x{}, expected {} pixels x {} images",
         observations.intensities.rows(), observations.intensities.cols(), observations.pixel_count(),
         observations.image_count());
  }
  Maps maps{cv::Mat(size, CV_32FC3, cv::Scalar::all(0)), cv::Mat(size, CV_32FC1, cv::Scalar::all(0)),
            cv::Mat(size, CV_32FC1, cv::Scalar::all(0)), cv::Mat(size, CV_8UC1, cv::Scalar::all(0)),
            cv::Mat()};
  if (options.confidence) {
    options.confidence->check();
    check_observations(observations, "solve_lambertian");  // the saturation flags the confidence reads
  }
  if (observations.near &&
      (observations.near->image_count() != observations.image_count() ||
       static_cast<std::size_t>(observations.near->points_mm.rows()) != observations.pixel_count())) {
    fail("solve_lambertian: near lights for {} images x {} pixels, observations have {} x {}",
         observations.near->image_count(), observations.near->points_mm.rows(), observations.image_count(),
         observations.pixel_count());
  }
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
