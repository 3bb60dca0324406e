#include "lightstage/host/eval/angular_error.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/geometry.hpp"
#include "lightstage/host/io/mask.hpp"
#include "lightstage/host/io/normal_map.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <system_error>
#include <vector>

namespace lightstage {
namespace {

bool present(const cv::Vec3f& n) {
  return std::isfinite(n[0]) && std::isfinite(n[1]) && std::isfinite(n[2]) && n.dot(n) > 1e-12f;
}

// Linear interpolation between order statistics (numpy's default).
// The q-quantile, interpolated between the two order statistics around it, as
// from the sorted values; `values` are partitioned from `from` on (what lies
// before it must be no larger than anything after it). Selection, not a sort:
// a megapixel's errors are sorted in about five times the time.
double percentile(std::vector<double>& values, std::size_t from, double q) {
  const double position = q * static_cast<double>(values.size() - 1);
  const auto below = static_cast<std::size_t>(std::floor(position));
  const auto at = values.begin() + static_cast<std::ptrdiff_t>(below);
  std::nth_element(values.begin() + static_cast<std::ptrdiff_t>(std::min(from, below)), at, values.end());
  const double lower = *at;
  const double upper = below + 1 < values.size() ? *std::min_element(at + 1, values.end()) : lower;
  return lower + (upper - lower) * (position - static_cast<double>(below));
}

}  // namespace

std::string AngularErrorStats::describe() const {
  std::string line = fmt::format(
      "angular error over {} pixels: mean {:.3f} deg, median {:.3f} deg, p90 {:.3f} deg, max {:.3f} deg",
      count, mean, median, p90, max);
  if (missing > 0) line += fmt::format(" ({} pixels without a prediction)", missing);
  return line;
}

nlohmann::json AngularErrorStats::to_json() const {
  return {{"mean_deg", mean}, {"median_deg", median}, {"p90_deg", p90},
          {"max_deg", max},   {"count", count},       {"missing", missing}};
}

namespace {

void check_maps(const cv::Mat& predicted, const cv::Mat& truth, const cv::Mat& mask) {
  if (predicted.type() != CV_32FC3 || truth.type() != CV_32FC3) {
    fail("angular_error: normal maps must be CV_32FC3, got types {} and {}", predicted.type(), truth.type());
  }
  if (predicted.size() != truth.size()) {
    fail("angular_error: predicted normals are {}x{}, ground truth is {}x{}", predicted.cols, predicted.rows,
         truth.cols, truth.rows);
  }
  if (!mask.empty() && (mask.type() != CV_8UC1 || mask.size() != truth.size())) {
    fail("angular_error: mask must be CV_8UC1 of {}x{}, got type {} of {}x{}", truth.cols, truth.rows,
         mask.type(), mask.cols, mask.rows);
  }
}

}  // namespace

void AngularErrorAccumulator::add(const cv::Mat& predicted, const cv::Mat& truth, const cv::Mat& mask,
                                  AngularErrorMap* map) {
  check_maps(predicted, truth, mask);
  for (int y = 0; y < truth.rows; ++y) {
    for (int x = 0; x < truth.cols; ++x) {
      if (!mask.empty() && mask.at<std::uint8_t>(y, x) == 0) continue;
      const cv::Vec3f& t = truth.at<cv::Vec3f>(y, x);
      if (!present(t)) continue;
      const cv::Vec3f& p = predicted.at<cv::Vec3f>(y, x);
      if (!present(p)) {
        ++missing_;
        continue;
      }
      const double angle = angle_between_deg(Vec3(p[0], p[1], p[2]), Vec3(t[0], t[1], t[2]));
      if (map != nullptr) {
        map->degrees.at<float>(y, x) = static_cast<float>(angle);
        map->valid.at<std::uint8_t>(y, x) = 255;
      }
      errors_.push_back(angle);
      sum_ += angle;
    }
  }
}

AngularErrorStats AngularErrorAccumulator::stats() {
  AngularErrorStats stats;
  stats.missing = missing_;
  stats.count = errors_.size();
  if (!errors_.empty()) {
    std::vector<double>& errors = errors_;
    stats.mean = sum_ / static_cast<double>(errors.size());
    stats.max = *std::max_element(errors.begin(), errors.end());
    stats.median = percentile(errors, 0, 0.5);
    // The median's selection left everything from its place on no smaller than what lies before.
    stats.p90 =
        percentile(errors, static_cast<std::size_t>(0.5 * static_cast<double>(errors.size() - 1)), 0.9);
  }
  return stats;
}

AngularErrorMap angular_error(const cv::Mat& predicted, const cv::Mat& truth, const cv::Mat& mask) {
  check_maps(predicted, truth, mask);
  AngularErrorMap result;
  result.degrees = cv::Mat(truth.size(), CV_32FC1, cv::Scalar::all(0));
  result.valid = cv::Mat(truth.size(), CV_8UC1, cv::Scalar::all(0));
  AngularErrorAccumulator accumulator;
  accumulator.add(predicted, truth, mask, &result);
  result.stats = accumulator.stats();
  return result;
}

AngularErrorStats evaluate_normal_map(const std::filesystem::path& predicted_png,
                                      const std::filesystem::path& truth_dir) {
  std::error_code error;
  if (!std::filesystem::is_directory(truth_dir, error))
    fail("{}: no such ground-truth folder", truth_dir.string());
  const auto truth_path = truth_dir / "Normal_gt.png";
  const auto mask_path = truth_dir / "mask.png";
  const auto predicted = io::read_normal_map(predicted_png);
  const auto truth = io::read_normal_map(truth_path);
  if (predicted.normals.size() != truth.normals.size()) {
    fail("{}: prediction is {}x{}, but {} is {}x{}", predicted_png.string(), predicted.normals.cols,
         predicted.normals.rows, truth_path.string(), truth.normals.cols, truth.normals.rows);
  }
  cv::Mat mask;
  if (std::filesystem::exists(mask_path, error)) {
    mask = io::read_mask(mask_path);
    if (mask.size() != truth.normals.size()) {
      fail("{}: mask is {}x{}, but {} is {}x{}", mask_path.string(), mask.cols, mask.rows,
           truth_path.string(), truth.normals.cols, truth.normals.rows);
    }
  }
  const AngularErrorStats stats = angular_error(predicted.normals, truth.normals, mask).stats;
  // Zero compared pixels would print as a perfect 0 degrees.
  if (stats.count == 0) {
    fail("{}: no pixel has both a prediction and ground truth in {}", predicted_png.string(),
         truth_dir.string());
  }
  return stats;
}

}  // namespace lightstage
