#pragma once
// Pictures of per-pixel maps for the report: false colour with a colour bar,
// the normal-map colour code and its reference sphere, a shaded depth relief.
// Every picture is CV_8UC4 (BGRA), transparent where the map has no value.

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <vector>

namespace lightstage::report {

// The colour maps the report uses (OpenCV's): viridis for magnitudes
// (residuals, error), inferno for depth.
inline constexpr int kMagnitudeColormap = cv::COLORMAP_VIRIDIS;
inline constexpr int kDepthColormap = cv::COLORMAP_INFERNO;

// `values` (CV_32FC1) mapped linearly from [low, high] onto `colormap`,
// clamped at both ends; transparent where `valid` (CV_8UC1) is 0 or the
// value is not finite.
cv::Mat false_colour(const cv::Mat& values, const cv::Mat& valid, double low, double high, int colormap);

// `count` colours (BGR) evenly spaced along `colormap`, low to high.
std::vector<cv::Vec3b> colormap_samples(int colormap, int count);

// Normals (CV_32FC3, x y z) as colour = round((n + 1) / 2 · 255), red = x.
cv::Mat normal_colours(const cv::Mat& normals, const cv::Mat& valid);

// The legend of that code: a unit sphere seen from the camera, `size` pixels square.
cv::Mat normal_sphere_legend(int size);

// A picture of linear `values` (CV_32FC1 grey, or CV_32FC3 BGR colour) scaled
// so that `scale` is white.
cv::Mat grey(const cv::Mat& values, const cv::Mat& valid, double scale);

// A relief of `depth` (CV_32FC1, z toward the camera) lit from the upper left:
// normals from central differences with `pixel_size` depth units per pixel.
cv::Mat shaded_depth(const cv::Mat& depth, const cv::Mat& valid, double pixel_size);

// A round number ≥ value (1, 2, 2.5 or 5 times a power of ten); 1 for value ≤ 0.
double nice_ceiling(double value);

}  // namespace lightstage::report
