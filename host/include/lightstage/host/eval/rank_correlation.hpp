#pragma once
// Spearman's rank correlation: how well one quantity orders another (a
// confidence map against the angular error it should predict), whatever
// monotonic scale either is on.

#include <opencv2/core.hpp>

#include <vector>

namespace lightstage {

// Spearman's ρ of two equally long samples (ties get their average rank).
// Throws InputError when the sizes differ or fewer than two values are given;
// 0 when either sample is constant.
double spearman_rho(const std::vector<double>& a, const std::vector<double>& b);

// ρ between two CV_32FC1 maps over the pixels where `valid` (CV_8UC1) is
// nonzero and both values are finite.
double spearman_rho(const cv::Mat& a, const cv::Mat& b, const cv::Mat& valid);

}  // namespace lightstage
