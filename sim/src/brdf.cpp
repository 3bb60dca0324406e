#include "lightstage/sim/brdf.hpp"

#include "lightstage/common/error.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdlib>

namespace lightstage::sim {
namespace {

bool above(const Vec3& n, const Vec3& l, const Vec3& v) { return n.dot(l) > 0 && n.dot(v) > 0; }

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

std::uint64_t hash_vec(const Vec3& a, std::uint64_t h) {
  for (int i = 0; i < 3; ++i) h = splitmix64(h ^ std::bit_cast<std::uint64_t>(a[i]));
  return h;
}

void require_positive(double value, const char* what) {
  if (!(value > 0) || !std::isfinite(value))
    fail("BRDF parameter '{}' must be positive, got {}", what, value);
}
void require_non_negative(double value, const char* what) {
  if (!(value >= 0) || !std::isfinite(value)) {
    fail("BRDF parameter '{}' must not be negative, got {}", what, value);
  }
}

}  // namespace

double hash_unit(std::uint64_t a, std::uint64_t b) {
  return static_cast<double>(splitmix64(splitmix64(a) ^ b) >> 11) * 0x1.0p-53;
}

double Lambert::eval(const Vec3& n, const Vec3& l, const Vec3& v) const { return above(n, l, v) ? 1.0 : 0.0; }

OrenNayar::OrenNayar(double sigma) : sigma_(sigma) {
  require_non_negative(sigma, "sigma");
  const double s2 = sigma * sigma;
  a_ = 1.0 - 0.5 * s2 / (s2 + 0.33);
  b_ = 0.45 * s2 / (s2 + 0.09);
}

double OrenNayar::eval(const Vec3& n, const Vec3& l, const Vec3& v) const {
  if (!above(n, l, v)) return 0;
  const double cl = std::min(n.dot(l), 1.0);
  const double cv = std::min(n.dot(v), 1.0);
  const Vec3 lp = l - cl * n;
  const Vec3 vp = v - cv * n;
  const double norms = lp.norm() * vp.norm();
  const double cos_phi = norms > 1e-12 ? std::max(0.0, lp.dot(vp) / norms) : 0.0;
  const double theta_l = std::acos(cl);
  const double theta_v = std::acos(cv);
  const double alpha = std::max(theta_l, theta_v);
  const double beta = std::min(theta_l, theta_v);
  return a_ + b_ * cos_phi * std::sin(alpha) * std::tan(beta);
}

std::string OrenNayar::describe() const { return fmt::format("oren-nayar:sigma={}", sigma_); }

namespace {
// Unpolarised Fresnel reflectance at a boundary into relative index eta,
// for an incidence cosine cos_i; total internal reflection gives 1.
double dielectric_fresnel(double cos_i, double eta) {
  cos_i = std::clamp(cos_i, 0.0, 1.0);
  const double sin_t2 = (1 - cos_i * cos_i) / (eta * eta);
  if (sin_t2 >= 1) return 1;
  const double cos_t = std::sqrt(1 - sin_t2);
  const double s = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
  const double p = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
  return 0.5 * (s * s + p * p);
}
}  // namespace

WolffDiffuse::WolffDiffuse(double eta) : eta_(eta) {
  if (!(eta > 1 && eta < 4)) fail("wolff: 'eta' must be in (1, 4), got {}", eta);
  scale_ = 1 / std::pow(1 - dielectric_fresnel(1, eta), 2);
}

double WolffDiffuse::eval(const Vec3& n, const Vec3& l, const Vec3& v) const {
  if (!above(n, l, v)) return 0;
  return scale_ * (1 - dielectric_fresnel(n.dot(l), eta_)) * (1 - dielectric_fresnel(n.dot(v), eta_));
}

std::string WolffDiffuse::describe() const { return fmt::format("wolff:eta={}", eta_); }

BlinnPhong::BlinnPhong(double shininess) : shininess_(shininess) { require_positive(shininess, "shininess"); }

double BlinnPhong::eval(const Vec3& n, const Vec3& l, const Vec3& v) const {
  if (!above(n, l, v)) return 0;
  const double nh = std::max(0.0, n.dot((l + v).normalized()));
  return (shininess_ + 8.0) / 8.0 * std::pow(nh, shininess_);
}

std::string BlinnPhong::describe() const { return fmt::format("blinn-phong:shininess={}", shininess_); }

CookTorrance::CookTorrance(double roughness, double f0) : m_(roughness), f0_(f0) {
  require_positive(roughness, "roughness");
  if (!(f0 >= 0 && f0 <= 1)) fail("BRDF parameter 'f0' must be in [0, 1], got {}", f0);
}

double CookTorrance::eval(const Vec3& n, const Vec3& l, const Vec3& v) const {
  if (!above(n, l, v)) return 0;
  const Vec3 h = (l + v).normalized();
  const double nh = n.dot(h);
  if (nh <= 0) return 0;
  const double nl = n.dot(l);
  const double nv = n.dot(v);
  const double vh = std::max(v.dot(h), 1e-12);
  const double nh2 = nh * nh;
  const double m2 = m_ * m_;
  const double d = std::exp((nh2 - 1.0) / (nh2 * m2)) / (kPi * m2 * nh2 * nh2);
  const double f = f0_ + (1.0 - f0_) * std::pow(1.0 - vh, 5.0);
  const double g = std::min({1.0, 2.0 * nh * nv / vh, 2.0 * nh * nl / vh});
  return kPi * d * f * g / (4.0 * nl * nv);
}

std::string CookTorrance::describe() const {
  return fmt::format("cook-torrance:roughness={},f0={}", m_, f0_);
}

Ward::Ward(double alpha) : alpha_(alpha) { require_positive(alpha, "alpha"); }

double Ward::eval(const Vec3& n, const Vec3& l, const Vec3& v) const {
  if (!above(n, l, v)) return 0;
  const Vec3 h = (l + v).normalized();
  const double nh = n.dot(h);
  if (nh <= 0) return 0;
  const double tan2 = (1.0 - nh * nh) / (nh * nh);
  const double a2 = alpha_ * alpha_;
  return std::exp(-tan2 / a2) / (4.0 * a2 * std::sqrt(n.dot(l) * n.dot(v)));
}

std::string Ward::describe() const { return fmt::format("ward:alpha={}", alpha_); }

FabricTwoLobe::FabricTwoLobe(double k1, double k2) : k1_(k1), k2_(k2) {
  require_non_negative(k1, "k1");
  require_non_negative(k2, "k2");
}

double FabricTwoLobe::eval(const Vec3& n, const Vec3& l, const Vec3& v) const {
  if (!above(n, l, v)) return 0;
  const Vec3 k = (v + 2.0 * l).normalized();
  return k1_ * std::max(0.0, n.dot(v)) + k2_ * std::max(0.0, n.dot(k));
}

std::string FabricTwoLobe::describe() const { return fmt::format("two-lobe-fabric:k1={},k2={}", k1_, k2_); }

RandomTwoLobe::RandomTwoLobe(double k1, double k2, std::uint64_t seed) : k1_(k1), k2_(k2), seed_(seed) {
  require_non_negative(k1, "k1");
  require_non_negative(k2, "k2");
}

double RandomTwoLobe::eval(const Vec3& n, const Vec3& l, const Vec3& v) const {
  if (!above(n, l, v)) return 0;
  const std::uint64_t h = hash_vec(l, hash_vec(n, seed_));
  // Uniform direction on the sphere from two hashed numbers.
  const double z = 2.0 * hash_unit(h, 1) - 1.0;
  const double phi = 2.0 * kPi * hash_unit(h, 2);
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  const Vec3 k(r * std::cos(phi), r * std::sin(phi), z);
  return k1_ * std::max(0.0, n.dot((l + v).normalized())) + k2_ * std::max(0.0, n.dot(k));
}

std::string RandomTwoLobe::describe() const {
  return fmt::format("two-lobe-random:k1={},k2={},seed={}", k1_, k2_, seed_);
}

PresetString parse_preset_string(const std::string& text, const std::string& what) {
  PresetString out;
  const auto colon = text.find(':');
  out.name = text.substr(0, colon);
  if (out.name.empty()) fail("{}: empty name in '{}'", what, text);
  if (colon == std::string::npos) return out;
  std::string rest = text.substr(colon + 1);
  std::size_t start = 0;
  while (start <= rest.size()) {
    const auto comma = std::min(rest.find(',', start), rest.size());
    const std::string item = rest.substr(start, comma - start);
    const auto eq = item.find('=');
    if (eq == std::string::npos || eq == 0)
      fail("{}: expected key=value, got '{}' in '{}'", what, item, text);
    const std::string key = item.substr(0, eq);
    const std::string value = item.substr(eq + 1);
    char* end = nullptr;
    const double number = std::strtod(value.c_str(), &end);
    if (value.empty() || end == nullptr || *end != '\0' || !std::isfinite(number)) {
      fail("{}: '{}' needs a number, got '{}' in '{}'", what, key, value, text);
    }
    if (!out.params.emplace(key, number).second) fail("{}: '{}' given twice in '{}'", what, key, text);
    start = comma + 1;
  }
  return out;
}

}  // namespace lightstage::sim
