#include "lightstage/host/surface/fusion.hpp"

#include "lightstage/common/error.hpp"
#include "surface/gradient_field.hpp"

#include <chrono>
#include <cmath>

namespace lightstage::surface {

void FusionOptions::check() const {
  if (!(lambda > 0) || !std::isfinite(lambda)) fail("fusion: lambda must be positive, got {}", lambda);
  if (reweight_iterations < 1 || reweight_iterations > 100)
    fail("fusion: reweight_iterations must be in 1..100, got {}", reweight_iterations);
  if (!(discontinuity_scale >= 0))
    fail("fusion: discontinuity_scale must be >= 0, got {}", discontinuity_scale);
  if (!(max_slope > 0)) fail("fusion: max_slope must be positive, got {}", max_slope);
  if (!(tolerance > 0 && tolerance < 1)) fail("fusion: tolerance must be in (0, 1), got {}", tolerance);
  if (max_iterations < 1) fail("fusion: max_iterations must be positive, got {}", max_iterations);
}

nlohmann::json FusionOptions::to_json() const {
  return {{"lambda", lambda},
          {"preserve_discontinuities", preserve_discontinuities},
          {"reweight_iterations", reweight_iterations},
          {"discontinuity_scale", discontinuity_scale},
          {"max_slope", max_slope},
          {"tolerance", tolerance},
          {"max_iterations", max_iterations}};
}

SurfaceResult fuse_depth_normals(const cv::Mat& prior, const cv::Mat& prior_valid, const cv::Mat& normals,
                                 const cv::Mat& mask, const CameraModel& camera, const FusionOptions& options,
                                 const SurfaceProgress& progress) {
  options.check();
  const auto start = std::chrono::steady_clock::now();
  const GradientField field = gradient_field(normals, mask, camera, options.max_slope, "fuse");
  if (prior.type() != CV_32FC1 || prior.size() != normals.size())
    fail("fuse: the depth prior must be CV_32FC1 of the normals' size {}x{}", normals.cols, normals.rows);
  if (!prior_valid.empty() && (prior_valid.type() != CV_8UC1 || prior_valid.size() != normals.size()))
    fail("fuse: the prior's validity mask must be CV_8UC1 of the normals' size");
  cv::Mat weight = cv::Mat::zeros(normals.size(), CV_64FC1);
  cv::Mat w_prior = cv::Mat::zeros(normals.size(), CV_64FC1);
  const double data = options.lambda * options.lambda;
  std::size_t used = 0;
  for (int r = 0; r < prior.rows; ++r) {
    for (int c = 0; c < prior.cols; ++c) {
      if (!field.inside.at<std::uint8_t>(r, c)) continue;
      if (!prior_valid.empty() && !prior_valid.at<std::uint8_t>(r, c)) continue;
      const double d = prior.at<float>(r, c);
      if (!std::isfinite(d) || (camera.perspective_model() && !(d > 0))) continue;
      weight.at<double>(r, c) = data;
      w_prior.at<double>(r, c) = to_w(d, camera);
      ++used;
    }
  }
  if (used == 0) fail("fuse: no pixel of the mask has a valid prior depth");
  const SurfaceSolveOptions s = SurfaceSolveOptions::from(options, progress);
  SurfaceResult result;
  const cv::Mat w = solve_surface(field, weight, w_prior, s, result.stats);
  result.depth = cv::Mat::zeros(normals.size(), CV_32FC1);
  result.valid = field.inside.clone();
  for (int r = 0; r < w.rows; ++r)
    for (int c = 0; c < w.cols; ++c)
      if (field.inside.at<std::uint8_t>(r, c))
        result.depth.at<float>(r, c) = static_cast<float>(from_w(w.at<double>(r, c), camera));
  result.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace lightstage::surface
