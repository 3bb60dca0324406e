#include "lightstage/host/solvers/normal_confidence.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/geometry.hpp"
#include "lightstage/common/parallel.hpp"
#include "lightstage/host/solvers/pixel_observations.hpp"

#include <Eigen/Dense>

#include <cmath>
#include <limits>

namespace lightstage {
namespace {

// Lit lights whose Gram matrix is this close to singular (smallest over
// largest eigenvalue) leave the normal undetermined.
constexpr double kMinEigenvalueRatio = 1e-6;

// A pixel's working arrays, kept from pixel to pixel.
struct Scratch {
  Eigen::VectorXd shading;
  Eigen::MatrixX3d counted;  // the counted lights' rows, zero elsewhere
};

double predict_pixel(const PixelObservations& data, const Eigen::Vector3d& n, double albedo,
                     double method_residual, const ConfidenceOptions& options, Scratch& scratch) {
  scratch.shading.noalias() = data.lights * n;
  scratch.counted.resize(data.count(), 3);
  double lit_sum = 0, lambert_squared = 0;
  int lit = 0;
  for (Eigen::Index j = 0; j < data.count(); ++j) {
    const double value = data.values(j), shading = scratch.shading(j);
    // Lit, and not from behind the answer (the model has no slope there).
    const bool counted =
        data.usable[static_cast<std::size_t>(j)] && value > options.shadow_threshold && shading > 0;
    if (!counted) {
      scratch.counted.row(j).setZero();
      continue;
    }
    scratch.counted.row(j) = data.lights.row(j);
    lit_sum += value;
    const double r = value - albedo * shading;
    lambert_squared += r * r;
    ++lit;
  }
  const double infinite = std::numeric_limits<double>::infinity();
  if (lit < 3 || !(albedo > 0)) return infinite;
  // The counted lights' Gram matrix, as one product (a light not counted adds zeros, whatever its row).
  const Eigen::Matrix3d gram = scratch.counted.transpose().lazyProduct(scratch.counted);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
  eigen.computeDirect(gram);
  const Eigen::Vector3d lambda = eigen.eigenvalues();
  if (!(lambda(0) > kMinEigenvalueRatio * lambda(2))) return infinite;
  const Eigen::Matrix3d& v = eigen.eigenvectors();
  const Eigen::Matrix3d inverse = v * lambda.cwiseInverse().asDiagonal() * v.transpose();
  const Eigen::Matrix3d tangent = Eigen::Matrix3d::Identity() - n * n.transpose();
  const double spread = std::sqrt(std::max(0.0, (tangent * inverse * tangent).trace()));
  double sigma = options.method_residual && std::isfinite(method_residual) ? method_residual
                                                                           : std::sqrt(lambert_squared / lit);
  sigma = std::max(sigma, options.min_relative_sigma * lit_sum / lit);
  return deg_from_rad(sigma / albedo * spread);
}

}  // namespace

void ConfidenceOptions::check() const {
  if (!(std::isfinite(shadow_threshold) && shadow_threshold >= 0))
    fail("ConfidenceOptions.shadow_threshold: must be finite and >= 0, got {}", shadow_threshold);
  if (!(std::isfinite(scale_deg) && scale_deg > 0))
    fail("ConfidenceOptions.scale_deg: must be finite and > 0, got {}", scale_deg);
  if (!(std::isfinite(min_relative_sigma) && min_relative_sigma >= 0))
    fail("ConfidenceOptions.min_relative_sigma: must be finite and >= 0, got {}", min_relative_sigma);
  if (threads < 0) fail("ConfidenceOptions.threads: must be 0 (automatic) or positive, got {}", threads);
}

nlohmann::json ConfidenceOptions::to_json() const {
  return {{"model", "lambertian curvature"},
          {"shadow_threshold", shadow_threshold},
          {"scale_deg", scale_deg},
          {"sigma", method_residual ? "method residual" : "lambertian residual"},
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
  const bool has_residual = !result.residual.empty() && result.residual.size() == observations.size;
  parallel_chunks(
      observations.pixel_count(), options.threads, [&](std::size_t, std::size_t begin, std::size_t end) {
        PixelObservations data;
        Scratch scratch;
        for (std::size_t p = begin; p < end; ++p) {
          const cv::Point& at = observations.pixels[p];
          if (result.solved.at<std::uint8_t>(at) == 0) continue;
          const cv::Vec3f& normal = result.normals.at<cv::Vec3f>(at);
          const Eigen::Vector3d n(normal[0], normal[1], normal[2]);
          if (!(n.norm() > 0.5)) continue;
          load_pixel(observations, p, true, data);
          const double residual =
              has_residual ? result.residual.at<float>(at) : std::numeric_limits<double>::quiet_NaN();
          error.at<float>(at) = static_cast<float>(
              predict_pixel(data, n.normalized(), result.albedo.at<float>(at), residual, options, scratch));
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
