#include "lightstage/host/solvers/normal_confidence.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/geometry.hpp"
#include "lightstage/common/parallel.hpp"
#include "lightstage/common/select_kth.hpp"
#include "lightstage/host/solvers/pixel_observations.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace lightstage {
namespace {

// Inliers whose Gram matrix is this close to singular (smallest over largest
// eigenvalue) leave the normal undetermined.
constexpr double kMinEigenvalueRatio = 1e-6;

// A pixel's working arrays, kept from pixel to pixel.
struct Scratch {
  Eigen::VectorXd shading;        // images: lᵀn
  Eigen::VectorXd misfit;         // images: |v − ρ lᵀn|, the Lambertian residual's size
  std::vector<std::uint8_t> lit;  // images: lit and facing the answer
  Eigen::MatrixX3d inlier_lights, weighted_lights;  // the inliers' l and |r| l, in their first rows
  Eigen::VectorXd inlier_values, inlier_weights;    // the inliers' v and |r|
  std::vector<double> magnitude;  // the lit lights' |residual| first, reordered to find the median
};

double predict_pixel(const PixelObservations& data, const Eigen::Vector3d& n, double albedo,
                     const ConfidenceOptions& options, Scratch& scratch) {
  const double infinite = std::numeric_limits<double>::infinity();
  if (!(albedo > 0 && std::isfinite(albedo))) return infinite;
  const Eigen::Index images = data.count();
  scratch.shading.noalias() = data.lights * n;
  scratch.misfit = (data.values - albedo * scratch.shading).cwiseAbs();
  if (scratch.inlier_lights.rows() < images) {
    scratch.lit.resize(static_cast<std::size_t>(images));
    scratch.magnitude.resize(static_cast<std::size_t>(images));
    scratch.inlier_lights.resize(images, 3);
    scratch.weighted_lights.resize(images, 3);
    scratch.inlier_values.resize(images);
    scratch.inlier_weights.resize(images);
  }
  // Written whatever the test says, kept by advancing: no branch to mispredict.
  std::size_t lit = 0;
  double lit_sum = 0;
  for (Eigen::Index j = 0; j < images; ++j) {
    const double value = data.values(j);
    // Lit, and not from behind the answer (the model has no slope there).
    const bool counted = data.usable[static_cast<std::size_t>(j)] && value > options.shadow_threshold &&
                         scratch.shading(j) > 0;
    scratch.lit[static_cast<std::size_t>(j)] = counted;
    scratch.magnitude[lit] = scratch.misfit(j);
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
                         : std::max(floor, options.trim * select_kth(scratch.magnitude.data(),
                                                                     static_cast<std::ptrdiff_t>(lit), half));
  // The inliers' lights, their values and their residuals' magnitudes (floored), packed.
  Eigen::Index inliers = 0;
  for (Eigen::Index j = 0; j < images; ++j) {
    const double magnitude = scratch.misfit(j);
    scratch.inlier_lights.row(inliers) = data.lights.row(j);
    scratch.inlier_values(inliers) = data.values(j);
    scratch.inlier_weights(inliers) = std::max(magnitude, floor);
    inliers += scratch.lit[static_cast<std::size_t>(j)] && magnitude <= cut ? 1 : 0;
  }
  if (inliers < 3) return infinite;
  const auto lights = scratch.inlier_lights.topRows(inliers);
  scratch.weighted_lights.topRows(inliers) = scratch.inlier_weights.head(inliers).asDiagonal() * lights;
  const auto weighted = scratch.weighted_lights.topRows(inliers);
  const Eigen::Matrix3d gram = lights.transpose().lazyProduct(lights);                      // Σ l lᵀ
  const Eigen::Matrix3d meat = weighted.transpose().lazyProduct(weighted);                  // Σ r² l lᵀ
  const Eigen::Vector3d moment = lights.transpose() * scratch.inlier_values.head(inliers);  // Σ v l
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
  const Eigen::Vector3d fitted = inverse * moment;
  const double disagreement = fitted.squaredNorm() > 0 ? angle_between_deg(fitted, n) : 180.0;
  return std::hypot(spread, disagreement);
}

}  // namespace

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
  parallel_chunks(observations.pixel_count(), options.threads,
                  [&](std::size_t, std::size_t begin, std::size_t end) {
                    PixelObservations data;
                    Scratch scratch;
                    for (std::size_t p = begin; p < end; ++p) {
                      const cv::Point& at = observations.pixels[p];
                      if (result.solved.at<std::uint8_t>(at) == 0) continue;
                      const cv::Vec3f& normal = result.normals.at<cv::Vec3f>(at);
                      const Eigen::Vector3d n(normal[0], normal[1], normal[2]);
                      if (!(n.norm() > 0.5)) continue;
                      load_pixel(observations, p, true, data);
                      error.at<float>(at) = static_cast<float>(
                          predict_pixel(data, n.normalized(), result.albedo.at<float>(at), options, scratch));
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
