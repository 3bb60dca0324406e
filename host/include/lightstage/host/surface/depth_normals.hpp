#pragma once
// Normals from a (coarse, noisy) depth map by plane PCA (dissertation Eq. 4.8,
// after Holz et al.): back-project every pixel with the camera, gather the 3-D
// points within distance `radius` of it, and take the direction of least
// variance of those points as its normal, oriented toward the camera. A larger
// radius suits a rougher depth map and gives smoother normals.

#include "lightstage/host/surface/camera.hpp"

#include <opencv2/core.hpp>

namespace lightstage::surface {

struct DepthNormalsOptions {
  // Neighbourhood radius in the depth's unit (mm for rig scenes and DiLiGenT).
  double radius = 2.0;
  // At most this many pixels are visited per window side; wider windows are
  // subsampled evenly (the plane fit needs a few dozen points, not thousands).
  int max_window_samples = 15;
  int min_points = 6;  // fewer neighbours: no normal
  int threads = 0;     // 0 = all cores

  void check() const;  // throws InputError naming the field
};

struct DepthNormals {
  cv::Mat normals;  // CV_32FC3 (x, y, z), unit where valid, zero elsewhere
  cv::Mat valid;    // CV_8UC1, 255 where a normal was fitted
};

// `depth`: CV_32FC1 depth values (camera.hpp); used where `valid` (CV_8UC1,
// empty = everywhere) is nonzero and the value is finite (and positive,
// perspective). Throws InputError for mismatched sizes or types.
DepthNormals normals_from_depth(const cv::Mat& depth, const cv::Mat& valid, const CameraModel& camera,
                                const DepthNormalsOptions& options = {});

}  // namespace lightstage::surface
