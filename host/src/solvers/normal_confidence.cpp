#include "lightstage/host/solvers/normal_confidence.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/parallel.hpp"
#include "lightstage/host/near_lights.hpp"
#include "lightstage/host/solvers/pixel_observations.hpp"
#include "solvers/confidence_lanes.hpp"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace lightstage {

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
  const Eigen::VectorXd reference =
      observations.near ? near_light_reference(*observations.near) : Eigen::VectorXd();
  parallel_chunks(observations.pixel_count(), options.threads,
                  [&](std::size_t, std::size_t begin, std::size_t end) {
                    // The judged pixels, kPixelLanes at a time.
                    LightLanes lanes;
                    ConfidenceLanes predictor(options);
                    std::size_t group[kPixelLanes];
                    Eigen::Vector3d normals[kPixelLanes];
                    double albedo[kPixelLanes], errors[kPixelLanes];
                    const bool judged[kPixelLanes] = {true, true, true, true};
                    std::size_t count = 0;
                    const auto flush = [&] {
                      load_light_lanes(observations, reference, group, count, lanes);
                      predictor.predict(lanes, normals, albedo, judged, errors);
                      for (std::size_t lane = 0; lane < count; ++lane)
                        error.at<float>(observations.pixels[group[lane]]) = static_cast<float>(errors[lane]);
                      count = 0;
                    };
                    for (std::size_t p = begin; p < end; ++p) {
                      const cv::Point& at = observations.pixels[p];
                      if (result.solved.at<std::uint8_t>(at) == 0) continue;
                      if (!judged_normal(result.normals.at<cv::Vec3f>(at), normals[count])) continue;
                      albedo[count] = result.albedo.at<float>(at);
                      group[count++] = p;
                      if (count == kPixelLanes) flush();
                    }
                    if (count > 0) flush();
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
