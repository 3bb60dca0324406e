#pragma once
// The bi-polynomial reflectance model (dissertation Chapter 3, Eq. 3.4), in
// its relaxed form, linear in its coefficients:
//   ρ(x, y) = Σ_{i=0..k} Σ_{j=0..k} C_ij x^i y^j,   x = n·h, y = l·h
// k = 1 bilinear (4 terms), 2 biquadratic (9), 3 bicubic (16). Coefficients
// are stored with C_ij at index i·(k+1) + j, so C_00 (the constant, the
// Lambertian part) comes first. ρ is the normalised BRDF (π f_r): a rendered
// value is ρ · max(n·l, 0).

#include "lightstage/common/geometry.hpp"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace lightstage {

inline constexpr int kMinBiPolynomialOrder = 1;
inline constexpr int kMaxBiPolynomialOrder = 3;

// (k + 1)²; order must be in [1, 3].
int bipolynomial_term_count(int order);

// Writes the (k + 1)² basis values x^i y^j into `out` (index i·(k+1) + j).
void bipolynomial_basis(int order, double x, double y, double* out);

// ρ(x, y) for `coefficients` of the given order.
double evaluate_bipolynomial(int order, const Eigen::Ref<const Eigen::VectorXd>& coefficients, double x,
                             double y);

// ρ for a normal, light and viewer (x = n·h, y = l·h).
double evaluate_bipolynomial(int order, const Eigen::Ref<const Eigen::VectorXd>& coefficients, const Vec3& n,
                             const Vec3& l, const Vec3& v = Vec3::UnitZ());

// The relighting model's optional specular lobe (reflectance/relighting_fit.hpp):
// Beckmann-shaped in θ_h, of width `roughness` (m), 1 at n·h = 1:
//   D = exp(−tan²θ_h / m²) / cos⁴θ_h,   cos θ_h = n·h (0 where n·h ≤ 0).
// Widths above kMaxLobeWidth (1/√2) would move its peak off n·h = 1.
inline constexpr double kMaxLobeWidth = 0.7;
double specular_lobe(double n_dot_h, double roughness);

// Coefficients per pixel of the relighting model: (k+1)², plus 1 with a lobe.
int relighting_term_count(int order, double lobe_width);

// ρ of the relighting model: the bi-polynomial of `order` in the first (k+1)²
// of `coefficients` plus, when lobe_roughness > 0, the next one times the
// lobe; clamped to ≥ 0 (as relighting renders it).
double evaluate_relighting_brdf(int order, double lobe_roughness, const float* coefficients, double n_dot_h,
                                double l_dot_h);

// The two parts of that ρ before the clamp: the bi-polynomial, which takes a
// colour stack's chroma, and the lobe, which stays white (dichromatic rule).
struct RelightingBrdfParts {
  double polynomial = 0;
  double lobe = 0;
};
RelightingBrdfParts evaluate_relighting_parts(int order, double lobe_roughness, const float* coefficients,
                                              double n_dot_h, double l_dot_h);

// "C00", "C01", ... in storage order.
std::vector<std::string> bipolynomial_term_names(int order);

// "bilinear", "biquadratic", "bicubic".
const char* bipolynomial_name(int order);

// Rank-1 factorisation C ≈ a bᵀ (ρ ≈ ρ1(x) ρ2(y), Eq. 3.3 / 3.5) by SVD; a[i]
// multiplies x^i and b[j] multiplies y^j. The signs are chosen so that the
// constant terms are non-negative.
struct FactorisedBiPolynomial {
  Eigen::VectorXd a, b;
  double relative_error = 0;  // |C − a bᵀ|_F / |C|_F
};
FactorisedBiPolynomial factorise_bipolynomial(int order,
                                              const Eigen::Ref<const Eigen::VectorXd>& coefficients);

}  // namespace lightstage
