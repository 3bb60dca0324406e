#include "lightstage/host/reflectance/bipolynomial_model.hpp"

#include "lightstage/common/error.hpp"

#include <Eigen/SVD>

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

namespace lightstage {

int bipolynomial_term_count(int order) {
  if (order < kMinBiPolynomialOrder || order > kMaxBiPolynomialOrder)
    fail("bi-polynomial order: must be 1 (bilinear), 2 (biquadratic) or 3 (bicubic), got {}", order);
  return (order + 1) * (order + 1);
}

void bipolynomial_basis(int order, double x, double y, double* out) {
  const int n = order + 1;
  double xi = 1;
  for (int i = 0; i < n; ++i) {
    double yj = 1;
    for (int j = 0; j < n; ++j) {
      out[i * n + j] = xi * yj;
      yj *= y;
    }
    xi *= x;
  }
}

double evaluate_bipolynomial(int order, const Eigen::Ref<const Eigen::VectorXd>& coefficients, double x,
                             double y) {
  const int n = order + 1;
  // Horner in x of polynomials in y.
  double result = 0;
  for (int i = n - 1; i >= 0; --i) {
    double row = 0;
    for (int j = n - 1; j >= 0; --j) row = row * y + coefficients(i * n + j);
    result = result * x + row;
  }
  return result;
}

double evaluate_bipolynomial(int order, const Eigen::Ref<const Eigen::VectorXd>& coefficients, const Vec3& n,
                             const Vec3& l, const Vec3& v) {
  const Vec3 h = (l + v).normalized();
  return evaluate_bipolynomial(order, coefficients, n.dot(h), l.dot(h));
}

namespace {
constexpr double kLobeCutoff = 700;  // exp(−700) ≈ 1e-304
}  // namespace

double specular_lobe(double n_dot_h, double roughness) {
  if (!(n_dot_h > 0) || !(roughness > 0)) return 0;
  const double c = std::min(n_dot_h, 1.0), c2 = c * c;
  const double exponent = (1 - c2) / (c2 * roughness * roughness);
  // Far down the tail exp(−t) is 0 long before 1/cos⁴ overflows (or makes 0/0).
  return exponent > kLobeCutoff ? 0.0 : std::exp(-exponent) / (c2 * c2);
}

int relighting_term_count(int order, double lobe_width) {
  return bipolynomial_term_count(order) + (lobe_width > 0 ? 1 : 0);
}

RelightingBrdfParts evaluate_relighting_parts(int order, double lobe_roughness, const float* coefficients,
                                              double n_dot_h, double l_dot_h) {
  const int n = order + 1;
  RelightingBrdfParts parts;
  for (int i = n - 1; i >= 0; --i) {
    double row = 0;
    for (int j = n - 1; j >= 0; --j) row = row * l_dot_h + coefficients[i * n + j];
    parts.polynomial = parts.polynomial * n_dot_h + row;
  }
  if (lobe_roughness > 0) parts.lobe = coefficients[n * n] * specular_lobe(n_dot_h, lobe_roughness);
  return parts;
}

double evaluate_relighting_brdf(int order, double lobe_roughness, const float* coefficients, double n_dot_h,
                                double l_dot_h) {
  const RelightingBrdfParts parts =
      evaluate_relighting_parts(order, lobe_roughness, coefficients, n_dot_h, l_dot_h);
  return std::max(parts.polynomial + parts.lobe, 0.0);
}

std::vector<std::string> bipolynomial_term_names(int order) {
  const int n = order + 1;
  std::vector<std::string> names;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) names.push_back(fmt::format("C{}{}", i, j));
  return names;
}

const char* bipolynomial_name(int order) {
  switch (order) {
    case 1:
      return "bilinear";
    case 2:
      return "biquadratic";
    case 3:
      return "bicubic";
    default:
      return "bipolynomial";
  }
}

FactorisedBiPolynomial factorise_bipolynomial(int order,
                                              const Eigen::Ref<const Eigen::VectorXd>& coefficients) {
  const int n = order + 1;
  Eigen::MatrixXd c(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) c(i, j) = coefficients(i * n + j);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(c, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const double s = svd.singularValues()(0);
  FactorisedBiPolynomial f;
  f.a = svd.matrixU().col(0) * std::sqrt(s);
  f.b = svd.matrixV().col(0) * std::sqrt(s);
  if (f.a(0) < 0) {
    f.a = -f.a;
    f.b = -f.b;
  }
  const double norm = c.norm();
  f.relative_error = norm > 0 ? (c - f.a * f.b.transpose()).norm() / norm : 0.0;
  return f;
}

}  // namespace lightstage
