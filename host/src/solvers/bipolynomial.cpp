#include "lightstage/host/solvers/bipolynomial.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/reflectance/bipolynomial_model.hpp"
#include "solvers/lambert_fit.hpp"
#include "solvers/pixel_driver.hpp"

#include <fmt/format.h>
#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <limits>

namespace lightstage {

void BiPolynomialOptions::check() const {
  if (order < kMinBiPolynomialOrder || order > kMaxBiPolynomialOrder)
    fail("BiPolynomialOptions.order: must be 1 (bilinear), 2 (biquadratic) or 3 (bicubic), got {}", order);
  if (!(t_low > 0 && t_low <= 1))
    fail("BiPolynomialOptions.t_low (--t-low): must be in (0, 1], got {}", t_low);
  if (!(std::isfinite(shadow_threshold) && shadow_threshold >= 0))
    fail("BiPolynomialOptions.shadow_threshold (--shadow-threshold): must be finite and >= 0, got {}",
         shadow_threshold);
  if (falloff && !(*falloff >= kMinFalloff && *falloff <= kMaxFalloff))
    fail("BiPolynomialOptions.falloff (--falloff): must be 'auto' or in [{}, {}], got {}", kMinFalloff,
         kMaxFalloff, *falloff);
  if (max_iterations < 1)
    fail("BiPolynomialOptions.max_iterations (--max-iterations): must be at least 1, got {}", max_iterations);
  if (!(tolerance >= 0 && std::isfinite(tolerance)))
    fail("BiPolynomialOptions.tolerance: must be finite and >= 0, got {}", tolerance);
  if (threads < 0)
    fail("BiPolynomialOptions.threads (--threads): must be 0 (automatic) or positive, got {}", threads);
}

nlohmann::json BiPolynomialOptions::to_json() const {
  return {{"order", order},
          {"model", bipolynomial_name(order)},
          {"t_low", t_low},
          {"shadow_threshold", shadow_threshold},
          {"falloff", falloff ? nlohmann::json(*falloff) : nlohmann::json("auto")},
          {"max_iterations", max_iterations},
          {"tolerance", tolerance},
          {"drop_saturated", drop_saturated},
          {"threads", threads}};
}

namespace {

// C = argmin |A C − i|² with A_j = (n·l_j) basis(x_j, y_j); returns the squared residual.
double solve_coefficients(int order, const Eigen::Vector3d& n, const PixelObservations& pixel,
                          BiPolynomialWorkspace& ws, Eigen::VectorXd& coefficients) {
  const int terms = bipolynomial_term_count(order);
  const auto m = static_cast<Eigen::Index>(ws.kept.size());
  ws.design.resize(m, terms);
  ws.target.resize(m);
  ws.basis.resize(terms);
  for (Eigen::Index r = 0; r < m; ++r) {
    const Eigen::Index j = ws.kept[static_cast<std::size_t>(r)];
    const Eigen::Vector3d l = pixel.lights.row(j).transpose();
    const Eigen::Vector3d h = ws.halves.row(j).transpose();
    bipolynomial_basis(order, n.dot(h), l.dot(h), ws.basis.data());
    ws.design.row(r) = n.dot(l) * ws.basis.transpose();
    ws.target(r) = pixel.values(j);
  }
  Eigen::MatrixXd gram = ws.design.transpose() * ws.design;
  // A whisper of ridge keeps nearly collinear terms solvable without biasing the fit.
  const double ridge = 1e-12 * std::max(gram.trace(), 1e-300);
  gram.diagonal().array() += ridge;
  coefficients = gram.ldlt().solve(ws.design.transpose() * ws.target);
  return (ws.design * coefficients - ws.target).squaredNorm();
}

}  // namespace

bool select_low_frequency(const PixelObservations& pixel, const BiPolynomialOptions& options,
                          BiPolynomialWorkspace& ws) {
  ws.candidates.clear();
  for (Eigen::Index j = 0; j < pixel.count(); ++j) {
    if (pixel.usable[static_cast<std::size_t>(j)] && pixel.values(j) > options.shadow_threshold)
      ws.candidates.push_back(j);
  }
  // Below terms + 2 observations the coefficients would interpolate noise exactly.
  const auto needed = static_cast<std::size_t>(bipolynomial_term_count(options.order) + 2);
  if (ws.candidates.size() < needed) return false;
  auto keep =
      static_cast<std::size_t>(std::ceil(options.t_low * static_cast<double>(ws.candidates.size()) - 1e-9));
  keep = std::clamp(keep, needed, ws.candidates.size());
  std::stable_sort(ws.candidates.begin(), ws.candidates.end(),
                   [&](Eigen::Index a, Eigen::Index b) { return pixel.values(a) < pixel.values(b); });
  ws.kept.assign(ws.candidates.begin(), ws.candidates.begin() + static_cast<std::ptrdiff_t>(keep));
  return true;
}

std::optional<FalloffEstimate> resolve_falloff(const Observations& observations,
                                               BiPolynomialOptions& options) {
  if (options.falloff) return std::nullopt;
  const FalloffEstimate estimate = options.falloff_estimate
                                       ? *options.falloff_estimate
                                       : estimate_incidence_falloff(observations, options);
  options.falloff = estimate.kappa;
  return estimate;
}

nlohmann::json falloff_json(const BiPolynomialOptions& options,
                            const std::optional<FalloffEstimate>& estimate) {
  nlohmann::json j = {{"kappa", options.falloff.value_or(0.0)}, {"estimated", estimate.has_value()}};
  if (estimate) {
    j["pixels"] = estimate->pixels;
    j["quartiles"] = {estimate->quartile_low, estimate->quartile_high};
  }
  return j;
}

BiPolynomialPixelFit fit_bipolynomial_pixel(const PixelObservations& pixel,
                                            const BiPolynomialOptions& options, BiPolynomialWorkspace& ws) {
  BiPolynomialPixelFit fit;
  const int order = options.order;
  const int terms = bipolynomial_term_count(order);
  const Eigen::Index images = pixel.count();
  if (!select_low_frequency(pixel, options, ws)) {
    fit.status = BiPolynomialPixelFit::Status::kTooFewObservations;
    return fit;
  }
  const std::size_t keep = ws.kept.size();
  fit.kept = static_cast<int>(keep);

  ws.halves.resize(images, 3);
  for (Eigen::Index j = 0; j < images; ++j)
    ws.halves.row(j) = (pixel.lights.row(j) + Eigen::RowVector3d(0, 0, 1)).normalized();

  // Initial normal: Lambert with the object's fall-off κ on the T_low set (a
  // degenerate fall-off fit keeps the Lambertian start).
  Eigen::Vector3d s;
  if (!detail::lambert_fit(pixel.lights, pixel.values, ws.kept, s) || s.norm() < 1e-12) return fit;
  Eigen::Vector3d n = s.normalized();
  const double kappa = options.falloff.value_or(0.0);
  if (kappa != 0 && ws.kept.size() >= kMinFalloffObservations) {
    // Not per pixel by residual: on the DiLiGenT ball that kept the biased
    // start wherever Lambert fit its T_low set better (docs/solvers.md).
    if (const auto start = fit_falloff_pixel(pixel, ws.kept, n, kappa)) n = start->normal;
  }

  Eigen::VectorXd coefficients;
  Eigen::Vector3d best_n = n;
  Eigen::VectorXd best_c;
  double best = std::numeric_limits<double>::infinity();
  double previous = std::numeric_limits<double>::infinity();
  int iteration = 0;
  for (;; ++iteration) {
    const double residual = solve_coefficients(order, n, pixel, ws, coefficients);
    if (!std::isfinite(residual)) break;
    if (residual < best) {
      best = residual;
      best_n = n;
      best_c = coefficients;
    }
    if (std::abs(previous - residual) < options.tolerance || iteration + 1 >= options.max_iterations) break;
    previous = residual;
    // Fix ρ_j at the current normal: i_j = ρ_j (l_j·n) is Lambertian with per-light albedo ρ_j.
    Eigen::Matrix3d gram = Eigen::Matrix3d::Zero();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
    for (const Eigen::Index j : ws.kept) {
      const Eigen::Vector3d h = ws.halves.row(j).transpose();
      const Eigen::Vector3d l = pixel.lights.row(j).transpose();
      const double rho = evaluate_bipolynomial(order, coefficients, n.dot(h), l.dot(h));
      const Eigen::Vector3d row = rho * l;
      gram.noalias() += row * row.transpose();
      rhs.noalias() += pixel.values(j) * row;
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
    eigen.computeDirect(gram);
    const Eigen::Vector3d lambda = eigen.eigenvalues();
    if (!(lambda(0) > detail::kCoplanarEigenvalueRatio * lambda(2))) break;
    const Eigen::Vector3d next =
        eigen.eigenvectors() * (eigen.eigenvectors().transpose() * rhs).cwiseQuotient(lambda);
    if (!next.allFinite() || next.norm() < 1e-12) break;
    n = next.normalized();
  }
  if (!std::isfinite(best) || best_c.size() != terms) return fit;

  fit.status = BiPolynomialPixelFit::Status::kSolved;
  fit.normal = best_n;
  fit.coefficients = best_c;
  fit.iterations = iteration + 1;
  fit.rms = std::sqrt(best / static_cast<double>(keep));
  double rho_sum = 0, value_sum = 0;
  for (const Eigen::Index j : ws.kept) {
    const Eigen::Vector3d h = ws.halves.row(j).transpose();
    rho_sum += evaluate_bipolynomial(order, best_c, best_n.dot(h), pixel.lights.row(j).dot(h));
    value_sum += pixel.values(j);
  }
  fit.albedo = rho_sum / static_cast<double>(keep);
  fit.mean_kept = value_sum / static_cast<double>(keep);
  return fit;
}

SolveFact mean_iterations_fact(double mean) {
  return {"mean_iterations", mean, fmt::format("{:.1f} iterations on average", mean)};
}

SolveResult solve_bipolynomial(const Observations& observations, const BiPolynomialOptions& given) {
  given.check();
  BiPolynomialOptions options = given;
  const auto estimate = resolve_falloff(observations, options);
  const int terms = bipolynomial_term_count(options.order);
  detail::DriverSettings settings;
  settings.method = bipolynomial_name(options.order);
  settings.threads = options.threads;
  settings.progress = options.progress;
  settings.drop_saturated = options.drop_saturated;
  settings.coefficient_count = terms;
  SolveResult result;
  const double iterations = detail::run_per_pixel(
      observations, settings,
      [&options]() -> detail::PixelCore {
        auto ws = std::make_shared<BiPolynomialWorkspace>();
        return [ws, &options](const PixelObservations& pixel, std::size_t, detail::PixelOutcome& out) {
          const BiPolynomialPixelFit fit = fit_bipolynomial_pixel(pixel, options, *ws);
          using S = BiPolynomialPixelFit::Status;
          if (fit.status == S::kTooFewObservations) {
            out.status = detail::PixelOutcome::Status::kTooFewObservations;
            return;
          }
          if (fit.status != S::kSolved) return;
          out.status = detail::PixelOutcome::Status::kSolved;
          out.normal = fit.normal;
          out.albedo = fit.albedo;
          out.residual = fit.rms;
          out.coefficients = fit.coefficients;
          out.iterations = fit.iterations;
        };
      },
      result);
  result.parameters = options.to_json();
  result.parameters["falloff"] = falloff_json(options, estimate);
  result.reflectance = {{"model", "bipolynomial"},
                        {"name", bipolynomial_name(options.order)},
                        {"order", options.order},
                        {"terms", bipolynomial_term_names(options.order)},
                        {"x", "n.h"},
                        {"y", "l.h"}};
  SolveSummary& s = result.summary;
  const double falloff = options.falloff.value_or(0.0);
  s.settings = {{"t_low", options.t_low, fmt::format("T_low {:.0f}%", 100 * options.t_low)},
                {"falloff", falloff, fmt::format("fall-off {:.3f}{}", falloff, estimate ? " estimated" : "")},
                {"falloff_estimated", estimate.has_value(), ""}};
  s.findings = {mean_iterations_fact(iterations)};
  s.message = s.format_message();
  return result;
}

}  // namespace lightstage
