#include "surface/gradient_field.hpp"

#include "lightstage/common/error.hpp"
#include "surface/grid_solver.hpp"

#include <algorithm>
#include <cmath>

namespace lightstage::surface {

GradientField gradient_field(const cv::Mat& normals, const cv::Mat& mask, const CameraModel& camera,
                             double max_slope, const char* what) {
  camera.check();
  if (normals.type() != CV_32FC3) fail("{}: normals must be CV_32FC3 (x, y, z)", what);
  if (normals.size() != camera.size)
    fail("{}: normals are {}x{} but the camera is {}x{}", what, normals.cols, normals.rows, camera.size.width,
         camera.size.height);
  if (!mask.empty() && (mask.type() != CV_8UC1 || mask.size() != normals.size()))
    fail("{}: mask must be CV_8UC1 of the normals' size {}x{}", what, normals.cols, normals.rows);
  GradientField f;
  f.gx = cv::Mat::zeros(normals.size(), CV_64FC1);
  f.gy = cv::Mat::zeros(normals.size(), CV_64FC1);
  f.has = cv::Mat::zeros(normals.size(), CV_8UC1);
  f.inside = mask.empty() ? cv::Mat(normals.size(), CV_8UC1, cv::Scalar(255)) : (mask != 0);
  const Mat3& K = camera.K;
  for (int r = 0; r < normals.rows; ++r) {
    for (int c = 0; c < normals.cols; ++c) {
      if (!f.inside.at<std::uint8_t>(r, c)) continue;
      const cv::Vec3f nf = normals.at<cv::Vec3f>(r, c);
      const Vec3 n(nf[0], nf[1], nf[2]);
      if (!n.allFinite() || n.norm() < 1e-6) continue;
      double gx = 0, gy = 0, slope = 0;
      if (!camera.perspective_model()) {
        // z = h(x, y): n ∝ (−h_x, −h_y, 1); rows grow downward, so ∂/∂row = −∂/∂y.
        const double nz = std::max(n.z(), 1e-9);
        gx = -n.x() / nz;
        gy = n.y() / nz;
        slope = std::hypot(gx, gy);
      } else {
        // In the x-right, y-down, z-forward frame n' = (nx, −ny, −nz) and
        // P = d (ũ, ṽ, 1); n'·∂P/∂u = 0 gives ∂log d/∂u = −n'x / (fx n'·(ũ, ṽ, 1)).
        const double u = (c - K(0, 2)) / K(0, 0), v = (r - K(1, 2)) / K(1, 1);
        const double denom = n.x() * u - n.y() * v - n.z();
        if (!(denom < -1e-9)) {
          slope = std::numeric_limits<double>::infinity();
          gx = -n.x();
          gy = n.y();
        } else {
          gx = -n.x() / (K(0, 0) * denom);
          gy = n.y() / (K(1, 1) * denom);
          // The slope in depth per pixel footprint, comparable to the orthographic one.
          slope = std::hypot(n.x(), n.y()) / -denom;
        }
        if (!std::isfinite(slope)) {
          // Facing away: keep the direction, clip the magnitude below.
          const double len = std::hypot(gx, gy);
          if (len == 0) continue;
          gx = gx / len * max_slope / K(0, 0);
          gy = gy / len * max_slope / K(1, 1);
          slope = 0;
        }
      }
      if (slope > max_slope) {
        gx *= max_slope / slope;
        gy *= max_slope / slope;
      }
      f.gx.at<double>(r, c) = gx;
      f.gy.at<double>(r, c) = gy;
      f.has.at<std::uint8_t>(r, c) = 255;
    }
  }
  return f;
}

namespace {

struct Edge {
  int r, c;
  bool horizontal;
  double g;
};

// Calls visit(edge) for each of the field's equations, always in the same
// order: neighbours both inside the mask, gradient from the ends that have one.
// Enumerated, never stored: at 24 Mpx a list of them takes 700 MB.
template <typename Visit>
void for_each_edge(const GradientField& f, Visit&& visit) {
  const int rows = f.inside.rows, cols = f.inside.cols;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      if (!f.inside.at<std::uint8_t>(r, c)) continue;
      const bool has_i = f.has.at<std::uint8_t>(r, c) != 0;
      for (const bool horizontal : {true, false}) {
        const int r2 = horizontal ? r : r + 1, c2 = horizontal ? c + 1 : c;
        if (r2 >= rows || c2 >= cols || !f.inside.at<std::uint8_t>(r2, c2)) continue;
        const bool has_j = f.has.at<std::uint8_t>(r2, c2) != 0;
        if (!has_i && !has_j) continue;
        const cv::Mat& g = horizontal ? f.gx : f.gy;
        const double gi = has_i ? g.at<double>(r, c) : 0, gj = has_j ? g.at<double>(r2, c2) : 0;
        visit(Edge{r, c, horizontal, (has_i && has_j) ? 0.5 * (gi + gj) : (has_i ? gi : gj)});
      }
    }
  }
}

double residual_of(const Edge& e, const std::vector<double>& w, int cols) {
  const std::size_t i = static_cast<std::size_t>(e.r) * cols + e.c;
  const std::size_t j = e.horizontal ? i + 1 : i + static_cast<std::size_t>(cols);
  return w[j] - w[i] - e.g;
}

}  // namespace

cv::Mat solve_surface(const GradientField& field, const cv::Mat& data_weight, const cv::Mat& w_prior,
                      const SurfaceSolveOptions& options, SurfaceStats& stats) {
  const int rows = field.inside.rows, cols = field.inside.cols;
  std::size_t edge_count = 0;
  for_each_edge(field, [&](const Edge&) { ++edge_count; });
  // Reweighting only: each edge's weight, in for_each_edge's order (1 = plain least squares).
  std::vector<double> weights;
  // The Cauchy weights' scale (reweighting only; the same every round).
  double sigma = options.scale;
  if (options.reweight && sigma <= 0) {
    double mean_g = 0;
    for_each_edge(field, [&](const Edge& e) { mean_g += std::abs(e.g) / static_cast<double>(edge_count); });
    // A fixed fraction of the typical gradient: residuals far above it are
    // what no smooth surface explains. (The residuals' own spread is no
    // guide: plain least squares smears a streak's error over everything.)
    // The mean, not the median: flat background must not shrink it.
    sigma = 0.07 * mean_g + 1e-9;
  }
  std::vector<double> w;
  stats = SurfaceStats{};
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) stats.pixels += field.inside.at<std::uint8_t>(r, c) ? 1 : 0;
  const int rounds = options.reweight ? options.reweight_iterations + 1 : 1;
  // Progress: round r covers [r, r + 1) / rounds; within it, the share of the
  // way from residual 1 to the round's tolerance on a log scale (what
  // conjugate gradients' roughly geometric convergence makes linear in time).
  double reported = 0;
  auto report = [&](double fraction) {
    if (options.progress && fraction > reported) {
      reported = fraction;
      options.progress(fraction);
    }
  };
  for (int round = 0; round < rounds; ++round) {
    GridSystem system(rows, cols);
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c)
        system.inside[system.index(r, c)] = field.inside.at<std::uint8_t>(r, c) ? 1 : 0;
    std::size_t k = 0;
    for_each_edge(field, [&](const Edge& e) {
      system.add_edge(e.r, e.c, e.horizontal, weights.empty() ? 1.0 : weights[k], e.g);
      ++k;
    });
    if (!data_weight.empty()) {
      for (int r = 0; r < rows; ++r) {
        for (int c = 0; c < cols; ++c) {
          const double d = data_weight.at<double>(r, c);
          if (d > 0 && system.inside[system.index(r, c)]) system.add_data(r, c, d, w_prior.at<double>(r, c));
        }
      }
    }
    // Intermediate reweighting rounds need only a rough solution.
    const bool last = round + 1 == rounds;
    const double tolerance = last ? options.tolerance : std::max(options.tolerance, 1e-4);
    std::function<void(double)> on_iteration;
    if (options.progress) {
      on_iteration = [&, round, tolerance](double residual) {
        const double share =
            residual <= tolerance ? 1.0 : std::clamp(std::log(residual) / std::log(tolerance), 0.0, 1.0);
        report((round + share) / rounds);
      };
    }
    const GridSolveStats s = solve_grid(system, w, tolerance, options.max_iterations, on_iteration);
    stats.solver_iterations += s.iterations;
    stats.relative_residual = s.relative_residual;
    if (last) break;
    // Cauchy weights from this round's residuals.
    weights.resize(edge_count);
    k = 0;
    for_each_edge(field, [&](const Edge& e) {
      const double t = std::abs(residual_of(e, w, cols)) / sigma;
      // A floor keeps the system well conditioned (and a cut edge still ties its ends weakly).
      weights[k++] = std::max(1.0 / (1.0 + t * t), 1e-3);
    });
    stats.reweight_rounds = round + 1;
  }
  report(1.0);
  double sum_sq = 0;
  for_each_edge(field, [&](const Edge& e) {
    const double residual = residual_of(e, w, cols);
    sum_sq += residual * residual;
  });
  stats.rms_gradient_residual = edge_count == 0 ? 0 : std::sqrt(sum_sq / static_cast<double>(edge_count));
  cv::Mat out(rows, cols, CV_64FC1);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) out.at<double>(r, c) = w[static_cast<std::size_t>(r) * cols + c];
  return out;
}

double to_w(double depth, const CameraModel& camera) {
  return camera.perspective_model() ? std::log(depth) : depth / camera.pixel_size;
}

double from_w(double w, const CameraModel& camera) {
  return camera.perspective_model() ? std::exp(w) : w * camera.pixel_size;
}

}  // namespace lightstage::surface
