#include "lightstage/host/surface/depth_normals.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/parallel.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <vector>

namespace lightstage::surface {
namespace {
constexpr double kMaxGrowth = 8;
}  // namespace

void DepthNormalsOptions::check() const {
  if (!(radius > 0) || !std::isfinite(radius))
    fail("normals from depth: radius must be positive, got {}", radius);
  if (max_window_samples < 3 || max_window_samples > 101)
    fail("normals from depth: max_window_samples must be in 3..101, got {}", max_window_samples);
  if (min_points < 3) fail("normals from depth: min_points must be at least 3, got {}", min_points);
  if (threads < 0) fail("normals from depth: threads must not be negative, got {}", threads);
}

DepthNormals normals_from_depth(const cv::Mat& depth, const cv::Mat& valid, const CameraModel& camera,
                                const DepthNormalsOptions& options) {
  options.check();
  camera.check();
  if (depth.type() != CV_32FC1) fail("normals from depth: depth must be CV_32FC1");
  if (depth.size() != camera.size)
    fail("normals from depth: depth is {}x{} but the camera is {}x{}", depth.cols, depth.rows,
         camera.size.width, camera.size.height);
  if (!valid.empty() && (valid.type() != CV_8UC1 || valid.size() != depth.size()))
    fail("normals from depth: the validity mask must be CV_8UC1 of the depth's size");
  const int rows = depth.rows, cols = depth.cols;
  // Back-projected points; NaN where there is no depth.
  std::vector<Vec3> points(static_cast<std::size_t>(rows) * cols, Vec3::Constant(std::nan("")));
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const double d = depth.at<float>(r, c);
      if ((!valid.empty() && !valid.at<std::uint8_t>(r, c)) || !std::isfinite(d)) continue;
      if (camera.perspective_model() && !(d > 0)) continue;
      points[static_cast<std::size_t>(r) * cols + c] = camera.point(c, r, d);
    }
  }
  DepthNormals out;
  out.normals = cv::Mat::zeros(depth.size(), CV_32FC3);
  out.valid = cv::Mat::zeros(depth.size(), CV_8UC1);
  parallel_chunks(
      static_cast<std::size_t>(rows), resolve_threads(options.threads),
      [&](std::size_t, std::size_t begin, std::size_t end) {
        for (int r = static_cast<int>(begin); r < static_cast<int>(end); ++r) {
          for (int c = 0; c < cols; ++c) {
            const Vec3& p = points[static_cast<std::size_t>(r) * cols + c];
            if (!p.allFinite()) continue;
            // The window that holds every point within the radius: the pixel
            // footprint at this depth converts the radius to pixels.
            const double footprint = camera.perspective_model()
                                         ? -p.z() / std::min(camera.K(0, 0), camera.K(1, 1))
                                         : camera.pixel_size;
            Vec3 sum = Vec3::Zero();
            Mat3 outer = Mat3::Zero();
            int n = 0;
            // On a steep slope few points lie within the radius (depth changes
            // fast across pixels): the radius doubles until enough do, up to
            // kMaxGrowth times, rather than leaving the steepest parts — the most
            // informative for the shape prior — without a normal.
            for (double radius = options.radius; radius <= kMaxGrowth * options.radius; radius *= 2) {
              const double r2 = radius * radius;
              const int half = static_cast<int>(std::min(std::ceil(radius / footprint), 4096.0));
              const int step =
                  std::max(1, (2 * half + 1 + options.max_window_samples - 1) / options.max_window_samples);
              sum.setZero();
              outer.setZero();
              n = 0;
              for (int dr = -half; dr <= half; dr += step) {
                const int rr = r + dr;
                if (rr < 0 || rr >= rows) continue;
                for (int dc = -half; dc <= half; dc += step) {
                  const int cc = c + dc;
                  if (cc < 0 || cc >= cols) continue;
                  const Vec3& q = points[static_cast<std::size_t>(rr) * cols + cc];
                  if (!q.allFinite()) continue;
                  const Vec3 d = q - p;  // relative to the centre: no cancellation at 1.5 m
                  if (d.squaredNorm() > r2) continue;
                  sum += d;
                  outer += d * d.transpose();
                  ++n;
                }
              }
              if (n >= options.min_points) break;
            }
            if (n < options.min_points) continue;
            const Vec3 mean = sum / n;
            const Mat3 cov = outer / n - mean * mean.transpose();
            const Eigen::SelfAdjointEigenSolver<Mat3> eig(cov);
            // Collinear points (a one-pixel line) have no plane.
            if (!(eig.eigenvalues()(1) > 1e-12 * std::max(eig.eigenvalues()(2), 1e-300))) continue;
            Vec3 normal = eig.eigenvectors().col(0);
            // Toward the camera: +z (orthographic) or against the viewing ray.
            const Vec3 toward = camera.perspective_model() ? Vec3(-p.normalized()) : Vec3::UnitZ();
            if (normal.dot(toward) < 0) normal = -normal;
            out.normals.at<cv::Vec3f>(r, c) =
                cv::Vec3f(static_cast<float>(normal.x()), static_cast<float>(normal.y()),
                          static_cast<float>(normal.z()));
            out.valid.at<std::uint8_t>(r, c) = 255;
          }
        }
      });
  return out;
}

}  // namespace lightstage::surface
