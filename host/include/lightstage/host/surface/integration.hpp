#pragma once
// Normal integration: depth from a normal map over an arbitrary mask.
//
// The unknown is w = depth / pixel_size (orthographic: height in pixels) or
// w = log(depth) (perspective: the log-depth gradients of a pinhole camera are
// a function of the normal and the pixel alone). Each pair of 4-neighbours
// inside the mask gives one equation w_j − w_i = (g_i + g_j)/2 from the
// normals' gradients g; the least-squares solution (a Poisson equation with
// natural boundary conditions) is computed with a multigrid-preconditioned
// conjugate-gradient solver (~1 s per megapixel).
//  - Frankot–Chellappa: the same least squares over the full rectangle, solved
//    in the Fourier domain (even extension, so the boundaries are not
//    periodic). Gradients outside the mask count as 0, so use it for full
//    rectangles.
//  - preserve_discontinuities: iteratively reweighted least squares with
//    Cauchy weights 1/(1 + (r/σ)²) on the equations' residuals, so where the
//    normals disagree with any smooth surface (a depth jump, an occluding
//    edge) the error stays at the jump instead of bending the surface around it.

#include "lightstage/host/surface/camera.hpp"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <functional>

namespace lightstage::surface {

enum class IntegrationMethod { kPoisson, kFrankotChellappa };
IntegrationMethod parse_integration_method(
    const std::string& text);  // "poisson" | "frankot-chellappa" | "fc"
const char* integration_method_name(IntegrationMethod method);

struct IntegrationOptions {
  IntegrationMethod method = IntegrationMethod::kPoisson;
  // Reweighting for depth discontinuities (Poisson only).
  bool preserve_discontinuities = false;
  int reweight_iterations = 6;
  // σ of the Cauchy weights, in units of w per pixel; 0 = 7% of the mean
  // gradient magnitude.
  double discontinuity_scale = 0;
  // Normals steeper than this slope (|∂depth/∂x| in pixel-size units) are
  // clipped to it: exactly grazing normals otherwise give unbounded
  // gradients. Only a guard (1000 = within 0.06° of grazing): a lower clip
  // flattens steep walls (DiLiGenT's objects: 1.7 mm mean error at 100,
  // 1.2 mm at 1000).
  double max_slope = 1000;
  // Perspective results are scaled to this mean depth (the integration
  // determines depth only up to scale); orthographic ones are shifted to mean 0.
  double perspective_mean_depth = 1.0;
  double tolerance = 1e-7;  // relative residual of the linear solves
  int max_iterations = 1000;

  void check() const;  // throws InputError naming the field
  nlohmann::json to_json() const;
};

struct SurfaceStats {
  int solver_iterations = 0;         // conjugate-gradient iterations, summed over reweighting rounds
  int reweight_rounds = 0;           // 0 without discontinuity preservation
  double relative_residual = 0;      // of the last linear solve
  double rms_gradient_residual = 0;  // RMS of (w_j − w_i − g) over the equations, w units
  double seconds = 0;
  std::size_t pixels = 0;

  nlohmann::json to_json() const;
};

struct SurfaceResult {
  cv::Mat depth;  // CV_32FC1, depth values as camera.hpp defines them, 0 outside `valid`
  cv::Mat valid;  // CV_8UC1, 255 where a depth was computed
  SurfaceStats stats;
};

// Optional progress report: the share of the work done, in [0, 1], never
// decreasing, ending at 1. For the iterative solves it is the share of the
// residual reduction achieved (log scale) in each reweighting round. Called on
// the caller's thread.
using SurfaceProgress = std::function<void(double fraction)>;

// Integrates `normals` (CV_32FC3 x y z, unit; zero = no normal) inside `mask`
// (CV_8UC1, nonzero = inside; empty = everywhere). Throws InputError for
// mismatched sizes or types.
SurfaceResult integrate_normals(const cv::Mat& normals, const cv::Mat& mask, const CameraModel& camera,
                                const IntegrationOptions& options = {}, const SurfaceProgress& progress = {});

}  // namespace lightstage::surface
