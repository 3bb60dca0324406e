#include "lightstage/host/solvers/incidence_falloff.hpp"

#include "lightstage/common/parallel.hpp"
#include "lightstage/host/solvers/bipolynomial.hpp"
#include "solvers/lambert_fit.hpp"

#include <Eigen/QR>

#include <algorithm>
#include <cmath>
#include <limits>

namespace lightstage {
namespace {

constexpr int kMaxIterations = 30;
constexpr double kConvergedRad = 1e-8;
constexpr double kMaxStepRad = 0.2;  // a Gauss–Newton step never turns the normal further
// Relative pivot below which a column counts as dependent (Eigen's default
// only catches exact rank loss; nearly collinear t, t² would vote a wild κ).
constexpr double kRankThreshold = 1e-9;

// The model's basis in t = n·l: free {t, t²}, or fixed κ {t + κt²}.
struct Basis {
  std::optional<double> kappa;
  int size() const { return kappa ? 1 : 2; }
  void at(double t, double* value, double* slope) const {
    if (kappa) {
      value[0] = t + *kappa * t * t;
      slope[0] = 1 + 2 * *kappa * t;
    } else {
      value[0] = t;
      slope[0] = 1;
      value[1] = t * t;
      slope[1] = 2 * t;
    }
  }
};

}  // namespace

std::optional<FalloffPixelFit> fit_falloff_pixel(const PixelObservations& pixel,
                                                 const std::vector<Eigen::Index>& kept,
                                                 const Eigen::Vector3d& start, std::optional<double> kappa) {
  const Basis basis{kappa};
  const int k = basis.size();
  const auto m = static_cast<Eigen::Index>(kept.size());
  if (m < k + 3) return std::nullopt;
  Eigen::Vector3d n = start.normalized();
  Eigen::MatrixXd design(m, k), jacobian(m, 2 + k);
  Eigen::VectorXd target(m), residual(m), coefficients(k);
  double value[2], slope[2];
  auto light = [&](Eigen::Index r) -> Eigen::Vector3d {
    return pixel.lights.row(kept[static_cast<std::size_t>(r)]).transpose();
  };
  for (Eigen::Index r = 0; r < m; ++r) target(r) = pixel.values(kept[static_cast<std::size_t>(r)]);
  // Variable projection: the coefficients are linear given n. False when t
  // and t² are (numerically) indistinguishable on these lights.
  auto project = [&]() {
    for (Eigen::Index r = 0; r < m; ++r) {
      basis.at(n.dot(light(r)), value, slope);
      for (int c = 0; c < k; ++c) design(r, c) = value[c];
    }
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(design);
    qr.setThreshold(kRankThreshold);
    if (qr.rank() < k) return false;
    coefficients = qr.solve(target);
    return coefficients.allFinite();
  };
  bool converged = false;
  for (int iteration = 0; iteration < kMaxIterations && !converged; ++iteration) {
    if (!project()) return std::nullopt;
    // One Gauss–Newton step on (tangent turn of n, coefficients) together.
    const Eigen::Vector3d u = n.unitOrthogonal();
    const Eigen::Vector3d w = n.cross(u);
    for (Eigen::Index r = 0; r < m; ++r) {
      const Eigen::Vector3d l = light(r);
      basis.at(n.dot(l), value, slope);
      double f = 0, df = 0;
      for (int c = 0; c < k; ++c) {
        f += coefficients(c) * value[c];
        df += coefficients(c) * slope[c];
        jacobian(r, 2 + c) = value[c];
      }
      residual(r) = target(r) - f;
      jacobian(r, 0) = df * u.dot(l);
      jacobian(r, 1) = df * w.dot(l);
    }
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> step_qr(jacobian);
    step_qr.setThreshold(kRankThreshold);
    if (step_qr.rank() < 2 + k) return std::nullopt;
    Eigen::Vector2d turn = step_qr.solve(residual).head<2>();
    if (!turn.allFinite()) return std::nullopt;
    converged = turn.norm() < kConvergedRad;
    if (turn.norm() > kMaxStepRad) turn *= kMaxStepRad / turn.norm();
    n = (n + turn(0) * u + turn(1) * w).normalized();
  }
  // A fit still turning after kMaxIterations oscillates: no answer.
  if (!converged || !project() || !n.allFinite() || !(coefficients(0) > 0)) return std::nullopt;
  FalloffPixelFit fit;
  fit.normal = n;
  fit.albedo = coefficients(0);
  fit.kappa = kappa ? *kappa : coefficients(1) / coefficients(0);
  if (!std::isfinite(fit.kappa)) return std::nullopt;
  return fit;
}

FalloffSamples::FalloffSamples(std::size_t total_pixels, std::size_t max_pixels) {
  const std::size_t most = max_pixels == 0 ? total_pixels : max_pixels;  // 0: every pixel
  stride_ = most == 0 ? 1 : std::max<std::size_t>(1, total_pixels / most + (total_pixels % most != 0));
}

void FalloffSamples::add(const Observations& observations, const BiPolynomialOptions& options) {
  check_observations(observations, "incidence fall-off");
  const std::size_t pixels = observations.pixel_count();
  // The first of these pixels on the whole image's stride (Observations::first_pixel).
  const std::size_t first = (stride_ - observations.first_pixel % stride_) % stride_;
  const std::size_t samples = first >= pixels ? 0 : (pixels - first + stride_ - 1) / stride_;
  std::vector<double> kappas(samples, std::numeric_limits<double>::quiet_NaN());
  parallel_chunks(samples, options.threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    PixelObservations pixel;
    BiPolynomialWorkspace ws;
    for (std::size_t s = begin; s < end; ++s) {
      load_pixel(observations, first + s * stride_, options.drop_saturated, pixel);
      if (!select_low_frequency(pixel, options, ws) || ws.kept.size() < kMinFalloffObservations) continue;
      Eigen::Vector3d lambert;
      if (!detail::lambert_fit(pixel.lights, pixel.values, ws.kept, lambert) || lambert.norm() < 1e-12)
        continue;
      const auto fit = fit_falloff_pixel(pixel, ws.kept, lambert, std::nullopt);
      if (fit) kappas[s] = fit->kappa;
    }
  });
  for (double k : kappas)
    if (std::isfinite(k)) kappas_.push_back(k);
}

FalloffEstimate FalloffSamples::estimate() const {
  std::vector<double> kappas = kappas_;
  FalloffEstimate estimate;
  estimate.pixels = kappas.size();
  if (kappas.size() < kMinFalloffPixels) return estimate;
  auto quantile = [&](double q) {
    const auto at = static_cast<std::ptrdiff_t>(q * static_cast<double>(kappas.size() - 1));
    std::nth_element(kappas.begin(), kappas.begin() + at, kappas.end());
    return kappas[static_cast<std::size_t>(at)];
  };
  estimate.kappa = std::clamp(quantile(0.5), kMinFalloff, kMaxFalloff);
  estimate.quartile_low = quantile(0.25);
  estimate.quartile_high = quantile(0.75);
  return estimate;
}

FalloffEstimate estimate_incidence_falloff(const Observations& observations,
                                           const BiPolynomialOptions& options, std::size_t max_pixels) {
  FalloffSamples samples(observations.pixel_count(), max_pixels);
  samples.add(observations, options);
  return samples.estimate();
}

}  // namespace lightstage
