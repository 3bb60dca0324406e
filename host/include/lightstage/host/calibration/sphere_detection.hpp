#pragma once
// Finding a calibration sphere's outline in the image, to sub-pixel accuracy:
// from an object mask (the midpoints between inside and outside pixels), or
// from an image in which the sphere stands out from the background (the
// median of a chrome-sphere stack: the sphere mirrors its lit surroundings),
// by a coarse blob search refined with half-level crossings along radial
// profiles. Both end in a geometric least-squares circle fit.

#include "lightstage/common/geometry.hpp"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace lightstage::calibration {

struct ImageCircle {
  Vec2 centre_px = Vec2::Zero();  // image point (pixel (c, r) centred at (c + 0.5, r + 0.5))
  double radius_px = 0;
  double rms_px = 0;            // RMS distance of the edge points from the circle
  std::size_t edge_points = 0;  // points fitted
  std::string source;           // "mask", "image" or "given"

  nlohmann::json to_json() const;
};

// Least-squares circle through `points`: algebraic (Kåsa) start, then
// Gauss–Newton on the geometric distances. Throws InputError when there are
// fewer than 3 points or they are (nearly) collinear.
ImageCircle fit_circle(const std::vector<Vec2>& points);

struct SphereDetectionOptions {
  int expected = 1;          // how many spheres the image holds
  double min_radius_px = 8;  // smaller blobs are not spheres
  double max_rms_px = 1.5;   // a blob whose outline is further from a circle is not a sphere
  int profiles = 720;        // radial profiles for the sub-pixel refinement

  // Throws InputError naming the broken field and value.
  void check() const;
};

// The spheres in a mask (CV_8UC1, non-zero = sphere), one per connected
// component of at least min_radius_px, largest first. `what` names the mask
// in messages. Throws InputError unless exactly options.expected are found.
std::vector<ImageCircle> circles_from_mask(const cv::Mat& mask, const SphereDetectionOptions& options,
                                           const std::string& what);

// The spheres in `image` (CV_32FC1): blobs brighter than the background that
// are circles, refined to sub-pixel. Throws InputError naming `what` when
// none, or a different number than options.expected, are found.
std::vector<ImageCircle> detect_circles(const cv::Mat& image, const SphereDetectionOptions& options,
                                        const std::string& what);

// Sub-pixel refinement of a circle already known to within a few pixels.
ImageCircle refine_circle(const cv::Mat& image, const ImageCircle& start, int profiles);

}  // namespace lightstage::calibration
