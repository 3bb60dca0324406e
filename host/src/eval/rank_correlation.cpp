#include "lightstage/host/eval/rank_correlation.hpp"

#include "lightstage/common/error.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace lightstage {
namespace {

// Ranks 1..n, ties sharing the mean of the ranks they span.
std::vector<double> ranks(const std::vector<double>& values) {
  std::vector<std::size_t> order(values.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return values[a] < values[b]; });
  std::vector<double> rank(values.size());
  for (std::size_t i = 0; i < order.size();) {
    std::size_t j = i;
    while (j + 1 < order.size() && values[order[j + 1]] == values[order[i]]) ++j;
    const double mean_rank = 0.5 * static_cast<double>(i + j) + 1.0;
    for (std::size_t k = i; k <= j; ++k) rank[order[k]] = mean_rank;
    i = j + 1;
  }
  return rank;
}

}  // namespace

double spearman_rho(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) fail("spearman_rho: samples of {} and {} values", a.size(), b.size());
  if (a.size() < 2) fail("spearman_rho: needs at least two values, got {}", a.size());
  const std::vector<double> ra = ranks(a), rb = ranks(b);
  const double mean = 0.5 * static_cast<double>(a.size() + 1);
  double cov = 0, va = 0, vb = 0;
  for (std::size_t i = 0; i < ra.size(); ++i) {
    cov += (ra[i] - mean) * (rb[i] - mean);
    va += (ra[i] - mean) * (ra[i] - mean);
    vb += (rb[i] - mean) * (rb[i] - mean);
  }
  if (va <= 0 || vb <= 0) return 0;
  return cov / std::sqrt(va * vb);
}

double spearman_rho(const cv::Mat& a, const cv::Mat& b, const cv::Mat& valid) {
  if (a.type() != CV_32FC1 || b.type() != CV_32FC1 || valid.type() != CV_8UC1 || a.size() != b.size() ||
      a.size() != valid.size())
    fail("spearman_rho: needs two CV_32FC1 maps and a CV_8UC1 mask of one size");
  std::vector<double> x, y;
  for (int r = 0; r < a.rows; ++r) {
    for (int c = 0; c < a.cols; ++c) {
      const float u = a.at<float>(r, c), v = b.at<float>(r, c);
      if (valid.at<std::uint8_t>(r, c) == 0 || !std::isfinite(u) || !std::isfinite(v)) continue;
      x.push_back(u);
      y.push_back(v);
    }
  }
  return spearman_rho(x, y);
}

}  // namespace lightstage
