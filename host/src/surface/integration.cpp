#include "lightstage/host/surface/integration.hpp"

#include "lightstage/common/error.hpp"
#include "surface/gradient_field.hpp"

#include <opencv2/core.hpp>

#include <chrono>
#include <cmath>

namespace lightstage::surface {
namespace {

// Frankot–Chellappa on the even extension of the surface: gx is odd across
// vertical mirrors and even across horizontal ones (gy the other way), so the
// 2W×2H periodic problem has the Neumann boundaries of the rectangle.
cv::Mat frankot_chellappa(const GradientField& f) {
  const int rows = f.gx.rows, cols = f.gx.cols;
  cv::Mat ex(2 * rows, 2 * cols, CV_64FC1), ey(2 * rows, 2 * cols, CV_64FC1);
  for (int r = 0; r < 2 * rows; ++r) {
    const bool flip_r = r >= rows;
    const int sr = flip_r ? 2 * rows - 1 - r : r;
    for (int c = 0; c < 2 * cols; ++c) {
      const bool flip_c = c >= cols;
      const int sc = flip_c ? 2 * cols - 1 - c : c;
      const bool use = f.has.at<std::uint8_t>(sr, sc) != 0;
      ex.at<double>(r, c) = use ? (flip_c ? -1.0 : 1.0) * f.gx.at<double>(sr, sc) : 0.0;
      ey.at<double>(r, c) = use ? (flip_r ? -1.0 : 1.0) * f.gy.at<double>(sr, sc) : 0.0;
    }
  }
  cv::Mat fx, fy;
  cv::dft(ex, fx, cv::DFT_COMPLEX_OUTPUT);
  cv::dft(ey, fy, cv::DFT_COMPLEX_OUTPUT);
  cv::Mat fz(fx.size(), CV_64FC2);
  const int R = fx.rows, C = fx.cols;
  for (int v = 0; v < R; ++v) {
    const double wy = 2 * kPi * (v <= R / 2 ? v : v - R) / R;
    for (int u = 0; u < C; ++u) {
      const double wx = 2 * kPi * (u <= C / 2 ? u : u - C) / C;
      const cv::Vec2d X = fx.at<cv::Vec2d>(v, u), Y = fy.at<cv::Vec2d>(v, u);
      // The least squares of the Poisson solver's equations, w_j − w_i =
      // (g_i + g_j)/2, in the Fourier domain: with D = e^{iω} − 1 and
      // A = (1 + e^{iω})/2, W = Σ conj(D) A G / Σ |D|² = −i Σ sin ω G / Σ 4 sin²(ω/2).
      const double sx = std::sin(wx), sy = std::sin(wy);
      const double den = 4 * (std::pow(std::sin(wx / 2), 2) + std::pow(std::sin(wy / 2), 2));
      if (den < 1e-12) {
        fz.at<cv::Vec2d>(v, u) = cv::Vec2d(0, 0);
        continue;
      }
      const double re = sx * X[1] + sy * Y[1];
      const double im = -(sx * X[0] + sy * Y[0]);
      fz.at<cv::Vec2d>(v, u) = cv::Vec2d(re / den, im / den);
    }
  }
  cv::Mat z;
  cv::idft(fz, z, cv::DFT_SCALE | cv::DFT_REAL_OUTPUT);
  return z(cv::Rect(0, 0, cols, rows)).clone();
}

}  // namespace

IntegrationMethod parse_integration_method(const std::string& text) {
  if (text == "poisson") return IntegrationMethod::kPoisson;
  if (text == "frankot-chellappa" || text == "fc") return IntegrationMethod::kFrankotChellappa;
  fail("integration method must be 'poisson' or 'frankot-chellappa', got '{}'", text);
}

const char* integration_method_name(IntegrationMethod method) {
  return method == IntegrationMethod::kPoisson ? "poisson" : "frankot-chellappa";
}

void IntegrationOptions::check() const {
  if (reweight_iterations < 1 || reweight_iterations > 100)
    fail("integration: reweight_iterations must be in 1..100, got {}", reweight_iterations);
  if (!(discontinuity_scale >= 0))
    fail("integration: discontinuity_scale must be >= 0, got {}", discontinuity_scale);
  if (!(max_slope > 0)) fail("integration: max_slope must be positive, got {}", max_slope);
  if (!(perspective_mean_depth > 0) || !std::isfinite(perspective_mean_depth))
    fail("integration: perspective_mean_depth must be positive, got {}", perspective_mean_depth);
  if (!(tolerance > 0 && tolerance < 1)) fail("integration: tolerance must be in (0, 1), got {}", tolerance);
  if (max_iterations < 1) fail("integration: max_iterations must be positive, got {}", max_iterations);
  if (preserve_discontinuities && method != IntegrationMethod::kPoisson)
    fail("integration: discontinuity preservation needs the Poisson method");
}

nlohmann::json IntegrationOptions::to_json() const {
  return {{"method", integration_method_name(method)},
          {"preserve_discontinuities", preserve_discontinuities},
          {"reweight_iterations", reweight_iterations},
          {"discontinuity_scale", discontinuity_scale},
          {"max_slope", max_slope},
          {"perspective_mean_depth", perspective_mean_depth},
          {"tolerance", tolerance},
          {"max_iterations", max_iterations}};
}

nlohmann::json SurfaceStats::to_json() const {
  return {{"solver_iterations", solver_iterations},
          {"reweight_rounds", reweight_rounds},
          {"relative_residual", relative_residual},
          {"rms_gradient_residual", rms_gradient_residual},
          {"seconds", seconds},
          {"pixels", pixels}};
}

SurfaceResult integrate_normals(const cv::Mat& normals, const cv::Mat& mask, const CameraModel& camera,
                                const IntegrationOptions& options, const SurfaceProgress& progress) {
  options.check();
  const auto start = std::chrono::steady_clock::now();
  const GradientField field = gradient_field(normals, mask, camera, options.max_slope, "integrate");
  SurfaceResult result;
  cv::Mat w;
  if (options.method == IntegrationMethod::kFrankotChellappa) {
    w = frankot_chellappa(field);
    result.stats.pixels = static_cast<std::size_t>(cv::countNonZero(field.inside));
    if (progress) progress(1.0);  // one direct solve
  } else {
    const SurfaceSolveOptions s = SurfaceSolveOptions::from(options, progress);
    w = solve_surface(field, {}, {}, s, result.stats);
  }
  // Fix the free constant: mean 0 (orthographic) or the requested mean depth (perspective).
  const double mean_w = cv::mean(w, field.inside)[0];
  result.depth = cv::Mat::zeros(normals.size(), CV_32FC1);
  result.valid = field.inside.clone();
  double mean_depth = 0;
  for (int r = 0; r < w.rows; ++r)
    for (int c = 0; c < w.cols; ++c)
      if (field.inside.at<std::uint8_t>(r, c)) mean_depth += from_w(w.at<double>(r, c) - mean_w, camera);
  // For perspective depths, exp(w − mean w) has geometric mean 1; rescale to an arithmetic mean.
  const double count = std::max<double>(1.0, static_cast<double>(cv::countNonZero(field.inside)));
  const double scale =
      camera.perspective_model() ? options.perspective_mean_depth / (mean_depth / count) : 1.0;
  for (int r = 0; r < w.rows; ++r)
    for (int c = 0; c < w.cols; ++c)
      if (field.inside.at<std::uint8_t>(r, c))
        result.depth.at<float>(r, c) =
            static_cast<float>(scale * from_w(w.at<double>(r, c) - mean_w, camera));
  result.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace lightstage::surface
