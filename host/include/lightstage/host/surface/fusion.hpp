#pragma once
// Depth–normal fusion (dissertation Eq. 4.9): a surface that follows the
// normals' gradients and stays near a (coarse, noisy) depth prior,
//     minimise  Σ_edges (w_j − w_i − g)²  +  λ² Σ_pixels (w_i − w_prior,i)²
// in the integration variable of integration.hpp (height in pixels,
// orthographic; log depth, perspective). Its normal equations are exactly
// Eq. 4.9's rows λ I Z = λ Z_prior and ∇² Z = ∂N (the divergence of the
// normals' gradient field), with natural boundary conditions at the mask's
// edge. λ trades the prior (large: follow the depth) against the normals
// (small: their shape, placed by the prior's low frequencies).

#include "lightstage/host/surface/integration.hpp"

namespace lightstage::surface {

struct FusionOptions {
  double lambda = 0.05;  // weight of the depth rows (per pixel, relative to one gradient equation)
  bool preserve_discontinuities = false;  // reweighting as in IntegrationOptions
  int reweight_iterations = 6;
  double discontinuity_scale = 0;
  double max_slope = 1000;
  double tolerance = 1e-7;
  int max_iterations = 1000;

  void check() const;  // throws InputError naming the field
  nlohmann::json to_json() const;
};

// Fuses `prior` (CV_32FC1 depth values as camera.hpp defines them; used where
// `prior_valid` is nonzero and the value is finite, and positive for a
// perspective camera) with `normals` inside `mask`. Pixels of the mask
// without a prior are filled from the normals. Throws InputError for
// mismatched sizes or types, or when no pixel has a prior.
SurfaceResult fuse_depth_normals(const cv::Mat& prior, const cv::Mat& prior_valid, const cv::Mat& normals,
                                 const cv::Mat& mask, const CameraModel& camera,
                                 const FusionOptions& options = {}, const SurfaceProgress& progress = {});

}  // namespace lightstage::surface
