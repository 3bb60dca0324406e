#include "lightstage/host/solvers/normal_confidence.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/geometry.hpp"
#include "lightstage/common/parallel.hpp"
#include "lightstage/common/select_kth.hpp"
#include "lightstage/host/solvers/pixel_observations.hpp"
#include "solvers/normal_equation_pairs.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

namespace lightstage {
namespace {

// Inliers whose Gram matrix is this close to singular (smallest over largest
// eigenvalue) leave the normal undetermined.
constexpr double kMinEigenvalueRatio = 1e-6;

}  // namespace

double PixelErrorPredictor::predict(const PixelObservations& data, const Eigen::Vector3d& n, double albedo) {
  const ConfidenceOptions& options = options_;
  const double infinite = std::numeric_limits<double>::infinity();
  if (!(albedo > 0 && std::isfinite(albedo))) return infinite;
  const Eigen::Index images = data.count();
  const auto count = static_cast<std::size_t>(images);
  if (misfit_.size() < count) {
    misfit_.resize(count);
    magnitude_.resize(count);
  }
  const double* lx = data.lights.col(0).data();
  const double* ly = data.lights.col(1).data();
  const double* lz = data.lights.col(2).data();
  const double* values = data.values.data();
  const double not_counted = std::numeric_limits<double>::quiet_NaN();
  // Written whatever the test says, kept by advancing: no branch to mispredict.
  std::size_t lit = 0;
  double lit_sum = 0;
  for (std::size_t j = 0; j < count; ++j) {
    const double value = values[j];
    const double shading = lx[j] * n.x() + ly[j] * n.y() + lz[j] * n.z();
    const double misfit = std::abs(value - albedo * shading);
    // Lit, and not from behind the answer (the model has no slope there).
    // Bitwise, not short-circuit: all three are cheap, and a branch on each would mispredict.
    const bool counted = (data.usable[j] != 0) & (value > options.shadow_threshold) & (shading > 0);
    // NaN compares false against any cut, an infinite one too.
    misfit_[j] = counted ? misfit : not_counted;
    magnitude_[lit] = misfit;
    lit += counted ? 1 : 0;
    lit_sum += counted ? value : 0.0;
  }
  if (lit < 3) return infinite;
  const double floor = options.min_relative_sigma * lit_sum / static_cast<double>(lit);
  // Three lit lights leave no spare one to judge them by: all are inliers (the
  // cut at twice their median would drop one whenever rounding decides).
  const auto half = static_cast<std::ptrdiff_t>(lit / 2);
  const double cut = lit == 3
                         ? infinite
                         : std::max(floor, options.trim * select_kth(magnitude_.data(),
                                                                     static_cast<std::ptrdiff_t>(lit), half));
  // The inliers' sums, two lights at a time (a vector's lanes): M = Σ l lᵀ,
  // Σ v l, and then S = Σ r² l lᵀ with r the residual's floored magnitude.
  // An outlier adds exact zeros; its value and residual are not read (either
  // may not be finite). Sums held in registers, so S takes a loop of its own.
  NormalEquationPairs sums;
  DoublePair inliers = {};
  double* squared = magnitude_.data();  // r² (0 for an outlier), the median taken
  const DoublePair cut2 = {cut, cut}, floor2 = {floor, floor}, zero = {}, one = {1.0, 1.0};
  const auto add = [&](const DoublePair lxj, const DoublePair lyj, const DoublePair lzj,
                       const DoublePair misfit, const DoublePair v) {
    const auto inlier = misfit <= cut2;
    sums.add(inlier, lxj, lyj, lzj, v);
    inliers += inlier ? one : zero;
    const DoublePair r = inlier ? (misfit < floor2 ? floor2 : misfit) : zero;
    return r * r;
  };
  std::size_t j = 0;
  for (; j + 2 <= count; j += 2) {
    const DoublePair r2 = add(load_pair(lx + j), load_pair(ly + j), load_pair(lz + j),
                              load_pair(misfit_.data() + j), load_pair(values + j));
    std::memcpy(squared + j, &r2, sizeof r2);
  }
  if (j < count) {  // the last light, in the first lane
    squared[j] = add(DoublePair{lx[j], 0.0}, DoublePair{ly[j], 0.0}, DoublePair{lz[j], 0.0},
                     DoublePair{misfit_[j], not_counted}, DoublePair{values[j], 0.0})[0];
  }
  DoublePair sandwich[6] = {};
  for (j = 0; j + 2 <= count; j += 2) {
    const DoublePair x = load_pair(lx + j), y = load_pair(ly + j), z = load_pair(lz + j),
                     r2 = load_pair(squared + j);
    sandwich[0] += r2 * (x * x);
    sandwich[1] += r2 * (x * y);
    sandwich[2] += r2 * (x * z);
    sandwich[3] += r2 * (y * y);
    sandwich[4] += r2 * (y * z);
    sandwich[5] += r2 * (z * z);
  }
  if (j < count) {
    const double x = lx[j], y = ly[j], z = lz[j], r2 = squared[j];
    const double outer[6] = {x * x, x * y, x * z, y * y, y * z, z * z};
    for (int k = 0; k < 6; ++k) sandwich[k][0] += r2 * outer[k];
  }
  if (inliers[0] + inliers[1] < 3) return infinite;
  const Eigen::Matrix3d gram = sums.gram_matrix();
  const Eigen::Matrix3d meat = symmetric_from_pairs(sandwich);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
  eigen.computeDirect(gram);
  const Eigen::Vector3d lambda = eigen.eigenvalues();
  if (!(lambda(0) > kMinEigenvalueRatio * lambda(2))) return infinite;
  const Eigen::Matrix3d& v = eigen.eigenvectors();
  const Eigen::Matrix3d inverse = v * lambda.cwiseInverse().asDiagonal() * v.transpose();
  const Eigen::Matrix3d tangent = Eigen::Matrix3d::Identity() - n * n.transpose();
  const Eigen::Matrix3d bread = tangent * inverse;
  const double spread =
      deg_from_rad(std::sqrt(std::max(0.0, (bread * meat * bread.transpose()).trace())) / albedo);
  const Eigen::Vector3d fitted = inverse * sums.moment_vector();
  const double disagreement = fitted.squaredNorm() > 0 ? angle_between_deg(fitted, n) : 180.0;
  return std::hypot(spread, disagreement);
}

bool judged_normal(const cv::Vec3f& stored, Eigen::Vector3d& n) {
  n = Eigen::Vector3d(stored[0], stored[1], stored[2]);
  if (!(n.norm() > 0.5)) return false;
  n.normalize();
  return true;
}

void ConfidenceOptions::check() const {
  if (!(std::isfinite(shadow_threshold) && shadow_threshold >= 0))
    fail("ConfidenceOptions.shadow_threshold: must be finite and >= 0, got {}", shadow_threshold);
  if (!(std::isfinite(scale_deg) && scale_deg > 0))
    fail("ConfidenceOptions.scale_deg: must be finite and > 0, got {}", scale_deg);
  if (!(std::isfinite(trim) && trim >= 1))
    fail("ConfidenceOptions.trim: must be finite and >= 1 (the median residual's lights are inliers), got {}",
         trim);
  if (!(std::isfinite(min_relative_sigma) && min_relative_sigma >= 0))
    fail("ConfidenceOptions.min_relative_sigma: must be finite and >= 0, got {}", min_relative_sigma);
  if (threads < 0) fail("ConfidenceOptions.threads: must be 0 (automatic) or positive, got {}", threads);
}

nlohmann::json ConfidenceOptions::to_json() const {
  return {{"model", "lambertian sandwich and disagreement"},
          {"shadow_threshold", shadow_threshold},
          {"scale_deg", scale_deg},
          {"trim", trim},
          {"min_relative_sigma", min_relative_sigma},
          {"confidence", "1 / (1 + predicted_error_deg / scale_deg)"}};
}

cv::Mat predict_normal_error(const Observations& observations, const SolveResult& result,
                             const ConfidenceOptions& options) {
  options.check();
  check_observations(observations, "predict_normal_error");
  if (result.normals.size() != observations.size || result.solved.size() != observations.size)
    fail("predict_normal_error: result maps are {}x{}, observations {}x{}", result.normals.cols,
         result.normals.rows, observations.size.width, observations.size.height);
  cv::Mat error(observations.size, CV_32FC1, cv::Scalar::all(0));
  parallel_chunks(
      observations.pixel_count(), options.threads, [&](std::size_t, std::size_t begin, std::size_t end) {
        PixelObservations data;
        PixelErrorPredictor predictor(options);
        Eigen::Vector3d n;
        for (std::size_t p = begin; p < end; ++p) {
          const cv::Point& at = observations.pixels[p];
          if (result.solved.at<std::uint8_t>(at) == 0) continue;
          if (!judged_normal(result.normals.at<cv::Vec3f>(at), n)) continue;
          load_pixel(observations, p, true, data);
          error.at<float>(at) = static_cast<float>(predictor.predict(data, n, result.albedo.at<float>(at)));
        }
      });
  return error;
}

cv::Mat confidence_from_error(const cv::Mat& error_deg, const cv::Mat& solved, double scale_deg) {
  if (error_deg.type() != CV_32FC1 || solved.type() != CV_8UC1 || error_deg.size() != solved.size())
    fail("confidence_from_error: needs a CV_32FC1 error map and a CV_8UC1 solved map of one size");
  cv::Mat confidence(error_deg.size(), CV_32FC1, cv::Scalar::all(0));
  for (int r = 0; r < error_deg.rows; ++r) {
    for (int c = 0; c < error_deg.cols; ++c) {
      if (solved.at<std::uint8_t>(r, c) == 0) continue;
      const double e = error_deg.at<float>(r, c);
      confidence.at<float>(r, c) = std::isfinite(e) ? static_cast<float>(1.0 / (1.0 + e / scale_deg)) : 0.0f;
    }
  }
  return confidence;
}

}  // namespace lightstage
