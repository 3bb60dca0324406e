#include "lightstage/host/reflectance/rti_basis.hpp"

#include "lightstage/common/error.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace lightstage {

RtiBasis parse_rti_basis(const std::string& name) {
  if (name == "ptm") return RtiBasis::ptm;
  if (name == "hsh2") return RtiBasis::hsh2;
  if (name == "hsh3") return RtiBasis::hsh3;
  fail("RTI model '{}' is not one of ptm, hsh2, hsh3", name);
}

const char* rti_basis_name(RtiBasis basis) {
  switch (basis) {
    case RtiBasis::ptm:
      return "ptm";
    case RtiBasis::hsh2:
      return "hsh2";
    case RtiBasis::hsh3:
      return "hsh3";
  }
  return "?";
}

int rti_term_count(RtiBasis basis) {
  switch (basis) {
    case RtiBasis::ptm:
      return 6;
    case RtiBasis::hsh2:
      return 4;
    case RtiBasis::hsh3:
      return 9;
  }
  return 0;
}

Eigen::VectorXd rti_weights(RtiBasis basis, const Vec3& light) {
  const Vec3 l = light.normalized();
  Eigen::VectorXd w(rti_term_count(basis));
  if (basis == RtiBasis::ptm) {
    w << l.x() * l.x(), l.y() * l.y(), l.x() * l.y(), l.x(), l.y(), 1.0;
    return w;
  }
  constexpr double pi = std::numbers::pi;
  // Lights below the horizon are folded onto it: the hemispherical basis is
  // defined for cos θ in [0, 1] only.
  const double ct = std::clamp(l.z(), 0.0, 1.0);
  const double phi = std::atan2(l.y(), l.x());
  const double st = std::sqrt(std::max(ct - ct * ct, 0.0));  // sqrt(cos θ - cos² θ)
  w(0) = 1.0 / std::sqrt(2 * pi);
  w(1) = std::sqrt(6 / pi) * std::cos(phi) * st;
  w(2) = std::sqrt(3 / (2 * pi)) * (-1 + 2 * ct);
  w(3) = std::sqrt(6 / pi) * st * std::sin(phi);
  if (basis == RtiBasis::hsh3) {
    w(4) = std::sqrt(30 / pi) * std::cos(2 * phi) * (-ct + ct * ct);
    w(5) = std::sqrt(30 / pi) * std::cos(phi) * (-1 + 2 * ct) * st;
    w(6) = std::sqrt(5 / (2 * pi)) * (1 - 6 * ct + 6 * ct * ct);
    w(7) = std::sqrt(30 / pi) * (-1 + 2 * ct) * st * std::sin(phi);
    w(8) = std::sqrt(30 / pi) * (-ct + ct * ct) * std::sin(2 * phi);
  }
  return w;
}

Eigen::MatrixXf fit_rti(RtiBasis basis, const Eigen::MatrixXf& values, const Eigen::MatrixX3d& lights) {
  const int terms = rti_term_count(basis);
  if (lights.rows() < terms)
    fail("{} fit: {} lights, at least {} needed", rti_basis_name(basis), lights.rows(), terms);
  if (values.cols() != lights.rows())
    fail("{} fit: {} values per pixel for {} lights", rti_basis_name(basis), values.cols(), lights.rows());
  Eigen::MatrixXd design(lights.rows(), terms);
  for (Eigen::Index i = 0; i < lights.rows(); ++i)
    design.row(i) = rti_weights(basis, lights.row(i).transpose()).transpose();
  // One pseudo-inverse for every pixel: all pixels see the same lights.
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(design);
  if (qr.rank() < terms)
    fail("{} fit: the {} lights do not determine {} terms (rank {})", rti_basis_name(basis), lights.rows(),
         terms, qr.rank());
  const Eigen::MatrixXd pinv = qr.solve(Eigen::MatrixXd::Identity(lights.rows(), lights.rows()));
  return (values.cast<double>() * pinv.transpose()).cast<float>();
}

Eigen::VectorXf evaluate_rti(RtiBasis basis, const Eigen::MatrixXf& coefficients, const Vec3& light) {
  return coefficients * rti_weights(basis, light).cast<float>();
}

}  // namespace lightstage
