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

std::optional<Vec2> predict_highlight(const MirrorSphere& sphere, const CameraGeometry& camera,
                                      const Vec3& led_mm) {
  const double r = sphere.radius_mm;
  if (!(r > 0) || !((led_mm - sphere.centre_mm).norm() > r)) return std::nullopt;
  // The normal at the mirror point bisects the directions to the camera and
  // to the LED; iterate n ← unit(v(x) + l(x)), x = c + r n. A contraction by
  // about r / distance per step: a handful of steps for a dome's LEDs.
  Vec3 n = (camera.toward_camera(sphere.centre_mm) + (led_mm - sphere.centre_mm).normalized()).normalized();
  bool converged = false;
  for (int iteration = 0; iteration < 200 && !converged; ++iteration) {
    const Vec3 x = sphere.centre_mm + r * n;
    const Vec3 next = (camera.toward_camera(x) + (led_mm - x).normalized()).normalized();
    if (!next.allFinite()) return std::nullopt;
    converged = (next - n).norm() < 1e-14;
    n = next;
  }
  if (!converged) return std::nullopt;
  const Vec3 x = sphere.centre_mm + r * n;
  if (!(n.dot(camera.toward_camera(x)) > 0) || !(n.dot(led_mm - x) > 0)) return std::nullopt;
  return camera.project(x);
}

std::optional<LedFit> refine_led_position(const std::vector<HighlightObservation>& observations,
                                          const CameraGeometry& camera, const Vec3& start_mm) {
  if (observations.size() < 2) return std::nullopt;
  // Whitened residuals W (predicted − measured), Wᵀ W = covariance⁻¹.
  std::vector<Eigen::Matrix2d> whiten;
  for (const auto& o : observations) {
    const Eigen::LLT<Eigen::Matrix2d> llt(o.covariance_px.inverse());
    if (llt.info() != Eigen::Success || !o.covariance_px.allFinite()) return std::nullopt;
    whiten.push_back(llt.matrixU());
  }
  const auto m = static_cast<Eigen::Index>(2 * observations.size());
  auto residuals = [&](const Vec3& p, Eigen::VectorXd* out) {
    out->resize(m);
    for (std::size_t k = 0; k < observations.size(); ++k) {
      const auto predicted = predict_highlight(observations[k].sphere, camera, p);
      if (!predicted) return false;
      out->segment<2>(static_cast<Eigen::Index>(2 * k)) =
          whiten[k] * (*predicted - observations[k].centre_px);
    }
    return true;
  };
  auto jacobian = [&](const Vec3& p, Eigen::MatrixXd* out) {
    out->resize(m, 3);
    const double h = 1e-4 * std::max(1.0, (p - observations.front().sphere.centre_mm).norm());
    Eigen::VectorXd plus, minus;
    for (int k = 0; k < 3; ++k) {
      Vec3 a = p, b = p;
      a(k) += h;
      b(k) -= h;
      if (!residuals(a, &plus) || !residuals(b, &minus)) return false;
      out->col(k) = (plus - minus) / (2 * h);
    }
    return true;
  };
  LedFit fit;
  fit.position_mm = start_mm;
  Eigen::VectorXd r;
  if (!residuals(fit.position_mm, &r)) return std::nullopt;
  double cost = r.squaredNorm(), lambda = 1e-4;
  Eigen::MatrixXd j;
  bool converged = false;
  for (int iteration = 0; iteration < 100 && !converged; ++iteration) {
    if (!jacobian(fit.position_mm, &j)) return std::nullopt;
    const Eigen::Matrix3d jtj = j.transpose() * j;
    const Eigen::Vector3d jtr = j.transpose() * r;
    bool improved = false;
    while (lambda < 1e12) {
      Eigen::Matrix3d damped = jtj;
      damped.diagonal() *= 1 + lambda;
      const Eigen::Vector3d step = damped.ldlt().solve(-jtr);
      Eigen::VectorXd next_r;
      const Vec3 next = fit.position_mm + step;
      if (step.allFinite() && residuals(next, &next_r) && next_r.squaredNorm() <= cost) {
        const double gain = cost - next_r.squaredNorm();
        fit.position_mm = next;
        r = next_r;
        cost = r.squaredNorm();
        lambda = std::max(lambda * 0.2, 1e-9);
        improved = true;
        fit.iterations = iteration + 1;
        converged = step.norm() < 1e-9 * std::max(1.0, next.norm()) || gain < 1e-12 * std::max(cost, 1e-12);
        break;
      }
      lambda *= 10;
    }
    if (!improved) break;
  }
  if (!jacobian(fit.position_mm, &j)) return std::nullopt;
  const Eigen::Matrix3d information = j.transpose() * j;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(information);
  // The smallest information must be a real one, not round-off: otherwise the
  // highlights leave a direction (the depth along parallel rays) undetermined.
  if (!(eigen.eigenvalues()(0) > 1e-12 * eigen.eigenvalues()(2))) return std::nullopt;
  fit.covariance_mm2 = information.inverse();
  fit.sigma_mm = std::sqrt(1 / eigen.eigenvalues()(0));
  fit.chi2 = cost;
  double sum = 0;
  for (std::size_t k = 0; k < observations.size(); ++k) {
    const auto predicted = predict_highlight(observations[k].sphere, camera, fit.position_mm);
    sum += (*predicted - observations[k].centre_px).squaredNorm();
  }
  fit.rms_px = std::sqrt(sum / static_cast<double>(observations.size()));
  return fit;
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
