#include "lightstage/host/calibration/led_positions.hpp"

#include "lightstage/common/error.hpp"

#include <Eigen/Dense>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace lightstage::calibration {

std::optional<Triangulation> triangulate(const std::vector<Ray>& rays, double min_conditioning) {
  if (rays.size() < 2) return std::nullopt;
  // Σ (I − d dᵀ)(p − o) = 0: the normal equations of the squared distances to the rays.
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (const auto& ray : rays) {
    const Eigen::Matrix3d projector = Eigen::Matrix3d::Identity() - ray.direction * ray.direction.transpose();
    a += projector;
    b += projector * ray.origin;
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(a);
  const Eigen::Vector3d lambda = eigen.eigenvalues();
  Triangulation result;
  result.conditioning = lambda(0) / lambda(2);
  if (!(result.conditioning > min_conditioning)) return std::nullopt;
  result.position_mm = a.ldlt().solve(b);
  result.rays = rays.size();
  double sum = 0;
  for (const auto& ray : rays) {
    const Vec3 offset = result.position_mm - ray.origin;
    const double distance = (offset - offset.dot(ray.direction) * ray.direction).norm();
    sum += distance * distance;
    result.max_mm = std::max(result.max_mm, distance);
  }
  result.rms_mm = std::sqrt(sum / static_cast<double>(rays.size()));
  return result;
}

std::optional<Vec3> intersect_dome(const Ray& ray, const Vec3& centre_mm, double radius_mm) {
  const Vec3 oc = ray.origin - centre_mm;
  const double b = ray.direction.dot(oc);
  const double disc = b * b - (oc.squaredNorm() - radius_mm * radius_mm);
  if (disc < 0) return std::nullopt;
  const double t = -b + std::sqrt(disc);
  if (t <= 0) return std::nullopt;
  return ray.origin + t * ray.direction;
}

nlohmann::json NominalFit::to_json() const {
  nlohmann::json r = nlohmann::json::array();
  for (int i = 0; i < 3; ++i) r.push_back({rotation(i, 0), rotation(i, 1), rotation(i, 2)});
  return {{"rotation", r},
          {"translation_mm", {translation.x(), translation.y(), translation.z()}},
          {"rotation_deg", rotation_deg},
          {"rms_mm", rms_mm},
          {"max_mm", max_mm}};
}

NominalFit fit_to_nominal(const std::vector<Vec3>& nominal, const std::vector<Vec3>& measured) {
  if (nominal.size() != measured.size())
    fail("nominal fit: {} nominal positions but {} measured", nominal.size(), measured.size());
  if (nominal.size() < 3) fail("nominal fit: {} LED position(s), at least 3 needed", nominal.size());
  const auto n = static_cast<Eigen::Index>(nominal.size());
  Eigen::Matrix3Xd src(3, n), dst(3, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    src.col(i) = nominal[static_cast<std::size_t>(i)];
    dst.col(i) = measured[static_cast<std::size_t>(i)];
  }
  const Eigen::Vector3d mean = src.rowwise().mean();
  const Eigen::Matrix3d spread = (src.colwise() - mean) * (src.colwise() - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(spread);
  if (!(eigen.eigenvalues()(1) > 1e-9 * eigen.eigenvalues()(2)))
    fail("nominal fit: the {} nominal positions are collinear", nominal.size());
  const Eigen::Matrix4d transform = Eigen::umeyama(src, dst, false);
  NominalFit fit;
  fit.rotation = transform.topLeftCorner<3, 3>();
  fit.translation = transform.topRightCorner<3, 1>();
  fit.rotation_deg = deg_from_rad(Eigen::AngleAxisd(fit.rotation).angle());
  double sum = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const Vec3 correction = dst.col(i) - (fit.rotation * src.col(i) + fit.translation);
    fit.corrections.push_back(correction);
    sum += correction.squaredNorm();
    fit.max_mm = std::max(fit.max_mm, correction.norm());
  }
  fit.rms_mm = std::sqrt(sum / static_cast<double>(n));
  return fit;
}

}  // namespace lightstage::calibration
