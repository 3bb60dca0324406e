#include "lightstage/host/solvers/sparse_regression.hpp"

#include "lightstage/common/error.hpp"
#include "solvers/lambert_fit.hpp"
#include "solvers/pixel_driver.hpp"

#include <fmt/format.h>
#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

namespace lightstage {
namespace {

// SBL stops when no error variance γ_j moved by more than this × (median value)².
constexpr double kGammaTolerance = 1e-8;

struct Workspace {
  std::vector<Eigen::Index> kept;
  std::vector<double> scratch;
  Eigen::VectorXd weights, gamma;
};

// The regression's observations: usable and above the shadow threshold. Returns the median kept value.
double select_lit(const PixelObservations& pixel, double shadow_threshold, Workspace& ws) {
  ws.kept.clear();
  ws.scratch.clear();
  for (Eigen::Index j = 0; j < pixel.count(); ++j) {
    if (pixel.usable[static_cast<std::size_t>(j)] && pixel.values(j) > shadow_threshold) {
      ws.kept.push_back(j);
      ws.scratch.push_back(pixel.values(j));
    }
  }
  if (ws.scratch.empty()) return 0;
  const auto mid = ws.scratch.begin() + static_cast<std::ptrdiff_t>(ws.scratch.size() / 2);
  std::nth_element(ws.scratch.begin(), mid, ws.scratch.end());
  return *mid;
}

// Normal, albedo and RMS residual over the kept observations.
void finish(const PixelObservations& pixel, const Workspace& ws, const Eigen::Vector3d& s,
            detail::PixelOutcome& out, int iterations) {
  if (!s.allFinite() || s.norm() < 1e-12) return;
  double squared = 0;
  for (const Eigen::Index j : ws.kept) {
    const double r = pixel.lights.row(j).dot(s) - pixel.values(j);
    squared += r * r;
  }
  const auto n = static_cast<double>(ws.kept.size());
  out.status = detail::PixelOutcome::Status::kSolved;
  out.normal = s;
  out.albedo = s.norm();
  out.residual = std::sqrt(squared / n);
  out.iterations = iterations;
}

void l1_pixel(const PixelObservations& pixel, const L1Options& options, Workspace& ws,
              detail::PixelOutcome& out) {
  const double median = select_lit(pixel, options.shadow_threshold, ws);
  if (static_cast<int>(ws.kept.size()) < options.min_observations) {
    out.status = detail::PixelOutcome::Status::kTooFewObservations;
    return;
  }
  Eigen::Vector3d s;
  if (!detail::lambert_fit(pixel.lights, pixel.values, ws.kept, s)) return;
  const double scale = std::max(median, 1e-12);
  const double epsilon = options.epsilon * scale;
  ws.weights.setZero(pixel.count());
  int it = 0;
  while (it < options.iterations) {
    ++it;
    for (const Eigen::Index j : ws.kept)
      ws.weights(j) = 1.0 / std::max(std::abs(pixel.lights.row(j).dot(s) - pixel.values(j)), epsilon);
    Eigen::Vector3d next;
    if (!detail::lambert_fit(pixel.lights, pixel.values, ws.kept, next, &ws.weights)) break;
    const double change = (next - s).norm();
    s = next;
    if (change < 1e-10 * std::max(s.norm(), 1e-12)) break;
  }
  finish(pixel, ws, s, out, it);
}

// EM for the sparse errors' variances γ (Tipping; Wipf & Rao), s integrated
// out under its flat prior. With Σ = λI + Γ diagonal (w = 1/diag Σ) and
// M = Lᵀ W L, the projected precision is P = W − W L M⁻¹ Lᵀ W, so
//   s = M⁻¹ Lᵀ W i,   r = i − L s,   ê = Γ W r,
//   Var(e_j) = γ_j − γ_j² P_jj,   γ_j ← ê_j² + Var(e_j).
void sbl_pixel(const PixelObservations& pixel, const SblOptions& options, Workspace& ws,
               detail::PixelOutcome& out) {
  const double median = select_lit(pixel, options.shadow_threshold, ws);
  if (static_cast<int>(ws.kept.size()) < options.min_observations) {
    out.status = detail::PixelOutcome::Status::kTooFewObservations;
    return;
  }
  Eigen::Vector3d s;
  if (!detail::lambert_fit(pixel.lights, pixel.values, ws.kept, s)) return;
  const double scale = std::max(median, 1e-12);
  const double lambda = options.noise * options.noise * scale * scale;
  ws.gamma.setZero(pixel.count());
  ws.weights.setZero(pixel.count());
  for (const Eigen::Index j : ws.kept) {  // start from the least-squares residuals
    const double r = pixel.values(j) - pixel.lights.row(j).dot(s);
    ws.gamma(j) = r * r + lambda;
  }
  int it = 0;
  while (it < options.iterations) {
    ++it;
    for (const Eigen::Index j : ws.kept) ws.weights(j) = 1.0 / (lambda + ws.gamma(j));
    Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
    for (const Eigen::Index j : ws.kept) {
      const Eigen::Vector3d l = pixel.lights.row(j).transpose();
      m.noalias() += ws.weights(j) * l * l.transpose();
      rhs.noalias() += ws.weights(j) * pixel.values(j) * l;
    }
    bool invertible = false;
    Eigen::Matrix3d m_inverse;
    m.computeInverseWithCheck(m_inverse, invertible);
    if (!invertible) break;
    const Eigen::Vector3d next = m_inverse * rhs;
    if (!next.allFinite()) break;
    double change = 0;
    for (const Eigen::Index j : ws.kept) {
      const Eigen::Vector3d l = pixel.lights.row(j).transpose();
      const double w = ws.weights(j), g = ws.gamma(j);
      const double r = pixel.values(j) - l.dot(next);
      const double p_jj = w - w * w * l.dot(m_inverse * l);
      const double e = g * w * r;
      const double updated = std::max(e * e + g - g * g * p_jj, 0.0);
      change = std::max(change, std::abs(updated - g));
      ws.gamma(j) = updated;
    }
    s = next;
    if (change < kGammaTolerance * scale * scale) break;
  }
  finish(pixel, ws, s, out, it);
}

template <typename Options, typename Core>
SolveResult solve_sparse(const Observations& observations, const Options& options, const char* method,
                         Core core) {
  options.check();
  SolveResult result;
  const double iterations = detail::run_per_pixel(
      observations, detail::driver_settings(method, options),
      [&options, core]() -> detail::PixelCore {
        auto ws = std::make_shared<Workspace>();
        return [ws, &options, core](const PixelObservations& pixel, std::size_t, detail::PixelOutcome& out) {
          core(pixel, options, *ws, out);
        };
      },
      result);
  result.parameters = options.to_json();
  result.summary.settings = {iterations_per_pixel_fact(iterations)};
  result.summary.message = result.summary.format_message();
  return result;
}

}  // namespace

SolveFact iterations_per_pixel_fact(double mean) {
  return {"iterations", mean, fmt::format("{:.1f} iterations per pixel", mean)};
}

void L1Options::check() const {
  detail::check_shadow_threshold("L1Options", shadow_threshold);
  if (iterations < 1) fail("L1Options.iterations: must be at least 1, got {}", iterations);
  if (!(epsilon > 0 && std::isfinite(epsilon))) fail("L1Options.epsilon: must be positive, got {}", epsilon);
  detail::check_min_observations("L1Options", min_observations);
  detail::check_threads("L1Options", threads);
}

nlohmann::json L1Options::to_json() const {
  return {{"shadow_threshold", shadow_threshold}, {"iterations", iterations},         {"epsilon", epsilon},
          {"min_observations", min_observations}, {"drop_saturated", drop_saturated}, {"threads", threads}};
}

void SblOptions::check() const {
  detail::check_shadow_threshold("SblOptions", shadow_threshold);
  if (iterations < 1) fail("SblOptions.iterations: must be at least 1, got {}", iterations);
  if (!(noise > 0 && std::isfinite(noise))) fail("SblOptions.noise: must be positive, got {}", noise);
  detail::check_min_observations("SblOptions", min_observations);
  detail::check_threads("SblOptions", threads);
}

nlohmann::json SblOptions::to_json() const {
  return {{"shadow_threshold", shadow_threshold}, {"iterations", iterations},         {"noise", noise},
          {"min_observations", min_observations}, {"drop_saturated", drop_saturated}, {"threads", threads}};
}

SolveResult solve_l1(const Observations& observations, const L1Options& options) {
  return solve_sparse(observations, options, "l1", l1_pixel);
}

SolveResult solve_sbl(const Observations& observations, const SblOptions& options) {
  return solve_sparse(observations, options, "sbl", sbl_pixel);
}

}  // namespace lightstage
