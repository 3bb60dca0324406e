#include "lightstage/host/solvers/auto.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/geometry.hpp"
#include "lightstage/host/reflectance/bipolynomial_model.hpp"
#include "solvers/pixel_driver.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace lightstage {
namespace {

// With every light this close to the view axis the monotonic candidate is
// not used: its elevation search needs lights over the hemisphere (on
// DiLiGenT's 43° cone it is 3.9° against the bi-polynomial's 1.2°, and the
// mean of the two where they agree is worse than the bi-polynomial answer).
// Nor is the BIC choice of order: there it prefers bilinear where
// biquadratic is the more accurate (the ball: 1.40° against 1.25°; the
// sweep's 43° cone with noise: auto 2.72 / 5.33° against biquadratic's
// 2.21 / 5.01°). auto is then the biquadratic answer.
constexpr double kMonotonicMinConeDeg = 60;

// What a pixel's answer came from (the method map), 1-based as SolveResult::choice counts.
enum Choice : std::uint8_t { kBiquadratic = 1, kBilinear, kMonotonic, kMean };
const std::vector<std::string> kChoiceNames = {"biquadratic", "bilinear", "monotonic", "mean"};

}  // namespace

void AutoOptions::check() const {
  bipolynomial.check();
  monotonic.check();
  if (bipolynomial.order != 2)
    fail("AutoOptions.bipolynomial.order: auto uses the biquadratic layout, got {}", bipolynomial.order);
  if (!(agreement_deg > 0 && agreement_deg <= 90))
    fail("AutoOptions.agreement_deg: must be in (0, 90], got {}", agreement_deg);
  if (!(monotonic_margin >= 0 && monotonic_margin <= 1))
    fail("AutoOptions.monotonic_margin: must be in [0, 1], got {}", monotonic_margin);
  if (threads < 0)
    fail("AutoOptions.threads (--threads): must be 0 (automatic) or positive, got {}", threads);
}

nlohmann::json AutoOptions::to_json() const {
  return {{"bipolynomial", bipolynomial.to_json()},
          {"monotonic", monotonic.to_json()},
          {"agreement_deg", agreement_deg},
          {"monotonic_margin", monotonic_margin},
          {"select_order", select_order},
          {"monotonic_min_cone_deg", kMonotonicMinConeDeg},
          {"threads", threads}};
}

SolveResult solve_auto(const Observations& observations, const AutoOptions& options) {
  options.check();
  BiPolynomialOptions bipolynomial = options.bipolynomial;
  MonotonicOptions monotonic = options.monotonic;
  bipolynomial.threads = monotonic.threads = options.threads;
  const auto falloff = resolve_falloff(observations, bipolynomial);
  double min_light_z = 1;
  for (Eigen::Index j = 0; j < observations.lights.rows(); ++j)
    min_light_z = std::min(min_light_z, observations.lights(j, 2));
  const double cone_deg = deg_from_rad(std::acos(std::clamp(min_light_z, -1.0, 1.0)));
  const bool use_monotonic = cone_deg >= kMonotonicMinConeDeg;
  detail::DriverSettings settings;
  settings.method = "auto";
  settings.threads = options.threads;
  settings.progress = options.progress;
  settings.drop_saturated = bipolynomial.drop_saturated;
  settings.coefficient_count = bipolynomial_term_count(bipolynomial.order);
  settings.choices = kChoiceNames;
  SolveResult result;
  BiPolynomialOptions bilinear = bipolynomial;
  bilinear.order = 1;
  struct Workspace {
    BiPolynomialWorkspace bipolynomial;
    MonotonicWorkspace monotonic;
  };
  detail::run_per_pixel(
      observations, settings,
      [&]() -> detail::PixelCore {
        auto ws = std::make_shared<Workspace>();
        return [ws, &bipolynomial, &bilinear, &monotonic, &options, use_monotonic](
                   const PixelObservations& pixel, std::size_t, detail::PixelOutcome& out) {
          BiPolynomialPixelFit fit = fit_bipolynomial_pixel(pixel, bipolynomial, ws->bipolynomial);
          if (fit.status == BiPolynomialPixelFit::Status::kTooFewObservations) {
            out.status = detail::PixelOutcome::Status::kTooFewObservations;
            return;
          }
          if (fit.status != BiPolynomialPixelFit::Status::kSolved) return;
          std::uint8_t bipolynomial_choice = kBiquadratic;
          if (options.select_order && use_monotonic) {
            const BiPolynomialPixelFit linear = fit_bipolynomial_pixel(pixel, bilinear, ws->bipolynomial);
            auto bic = [](const BiPolynomialPixelFit& f, int terms) {
              const double m = f.kept;
              return m * std::log(std::max(f.rms * f.rms, 1e-300)) + terms * std::log(m);
            };
            if (linear.status == BiPolynomialPixelFit::Status::kSolved && linear.kept == fit.kept &&
                bic(linear, 4) < bic(fit, 9)) {
              // The biquadratic layout: C_ij at i·3 + j.
              Eigen::VectorXd c = Eigen::VectorXd::Zero(9);
              c(0) = linear.coefficients(0);
              c(1) = linear.coefficients(1);
              c(3) = linear.coefficients(2);
              c(4) = linear.coefficients(3);
              fit = linear;
              fit.coefficients = c;
              bipolynomial_choice = kBilinear;
            }
          }
          const Eigen::Vector3d nb = fit.normal;
          out.status = detail::PixelOutcome::Status::kSolved;
          out.albedo = fit.albedo;
          out.residual = fit.rms;
          out.coefficients = fit.coefficients;
          out.iterations = fit.iterations;
          out.choice = bipolynomial_choice;
          if (!use_monotonic) {
            out.normal = nb;
            return;
          }
          const double phi = std::atan2(nb.y(), nb.x());
          prepare_monotonic(pixel, ws->monotonic);
          const ElevationEstimate e = search_elevation(phi, monotonic, ws->monotonic);
          Eigen::Vector3d nm = direction_from_elevation_azimuth(e.elevation, phi);
          if (monotonic.refine_step_deg > 0)
            nm = refine_normal(nm, monotonic.refine_step_deg, monotonic, ws->monotonic);
          const double apart_deg = deg_from_rad(std::atan2(nb.cross(nm).norm(), nb.dot(nm)));
          Eigen::Vector3d n = nb;
          if (apart_deg <= options.agreement_deg) {
            n = (nb + nm).normalized();
            out.choice = kMean;
          } else {
            const double sm = profile_monotonicity(pixel, nm, monotonic.shadow_threshold);
            const double sb = profile_monotonicity(pixel, nb, monotonic.shadow_threshold);
            if (sm - sb >= options.monotonic_margin) {
              n = nm;
              out.choice = kMonotonic;
            }
          }
          out.normal = n;
        };
      },
      result);
  result.parameters = options.to_json();
  result.parameters["bipolynomial"]["falloff"] = falloff_json(bipolynomial, falloff);
  result.reflectance = {{"model", "bipolynomial"},
                        {"name", bipolynomial_name(bipolynomial.order)},
                        {"order", bipolynomial.order},
                        {"terms", bipolynomial_term_names(bipolynomial.order)},
                        {"x", "n.h"},
                        {"y", "l.h"}};
  SolveSummary& s = result.summary;
  nlohmann::json counts = nlohmann::json::object();
  for (std::size_t k = 0; k < kChoiceNames.size(); ++k)
    counts[kChoiceNames[k]] =
        static_cast<std::size_t>(cv::countNonZero(result.choice == static_cast<int>(k + 1)));
  s.findings.push_back(method_counts_fact(counts, s.pixels_solved));
  const std::string model = bipolynomial_name(bipolynomial.order);
  if (use_monotonic) {
    s.settings = {{"models", {model, "monotonic"}, model + " + monotonic"}};
  } else {
    s.settings = {{"models",
                   {model},
                   fmt::format("{} only: lights within {:.0f} deg", bipolynomial_name(2), cone_deg)}};
  }
  s.message = s.format_message();
  return result;
}

SolveFact method_counts_fact(const nlohmann::json& counts, std::size_t solved) {
  std::string shares;
  // In the choices' order (SolveResult::choices), not the JSON object's alphabetical one.
  for (const std::string& name : kChoiceNames) {
    const auto count = counts.value(name, std::size_t{0});
    if (count == 0 || solved == 0) continue;
    shares += fmt::format("{}{} {:.0f}%", shares.empty() ? "" : ", ", name,
                          100.0 * static_cast<double>(count) / static_cast<double>(solved));
  }
  return {"method_counts", counts, shares.empty() ? std::string{} : "from " + shares};
}

}  // namespace lightstage
