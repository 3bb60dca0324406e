#pragma once
// What integration and fusion share: the normals' gradient field in the
// integration variable (see integration.hpp), the least-squares system over
// the mask, the reweighting loop and the conversion back to depth.

#include "lightstage/host/surface/camera.hpp"
#include "lightstage/host/surface/integration.hpp"

#include <opencv2/core.hpp>

#include <vector>

namespace lightstage::surface {

struct GradientField {
  cv::Mat gx, gy;  // CV_64FC1: ∂w/∂col, ∂w/∂row
  cv::Mat has;     // CV_8UC1: the pixel has a usable normal
  cv::Mat inside;  // CV_8UC1: the pixel is an unknown (inside the mask)
};

// Checks types and sizes (naming `what` in errors) and computes the field.
GradientField gradient_field(const cv::Mat& normals, const cv::Mat& mask, const CameraModel& camera,
                             double max_slope, const char* what);

struct SurfaceSolveOptions {
  bool reweight = false;
  int reweight_iterations = 6;
  double scale = 0;  // Cauchy σ; 0 = automatic
  double tolerance = 1e-7;
  int max_iterations = 1000;
  SurfaceProgress progress;  // integration.hpp; empty = none

  // From IntegrationOptions or FusionOptions (the same solver flags).
  template <typename Options>
  static SurfaceSolveOptions from(const Options& options, const SurfaceProgress& progress) {
    SurfaceSolveOptions s;
    s.reweight = options.preserve_discontinuities;
    s.reweight_iterations = options.reweight_iterations;
    s.scale = options.discontinuity_scale;
    s.tolerance = options.tolerance;
    s.max_iterations = options.max_iterations;
    s.progress = progress;
    return s;
  }
};

// Least squares over the field's edges plus data_weight·(w − w_prior)² where
// data_weight > 0 (both CV_64FC1, or empty for none). Returns w (CV_64FC1,
// 0 outside) and fills the statistics except the time.
cv::Mat solve_surface(const GradientField& field, const cv::Mat& data_weight, const cv::Mat& w_prior,
                      const SurfaceSolveOptions& options, SurfaceStats& stats);

// depth → w and back (camera.hpp depth values).
double to_w(double depth, const CameraModel& camera);
double from_w(double w, const CameraModel& camera);

}  // namespace lightstage::surface
