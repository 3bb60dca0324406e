#include "lightstage/pipeline/solve_methods.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/host/reflectance/bipolynomial_model.hpp"
#include "lightstage/host/reflectance/relighting_fit.hpp"
#include "lightstage/host/solvers/normal_confidence.hpp"
#include "lightstage/pipeline/shape_prior_method.hpp"
#include "lightstage/pipeline/solve_checks.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <utility>

namespace lightstage::pipeline {
namespace {

SolveResult solve_bipolynomial_order(const Observations& obs, const SolveSettings& settings, int order) {
  BiPolynomialOptions options = settings.bipolynomial;
  options.order = order;
  return solve_bipolynomial(obs, options);
}

// The azimuth from isotropy (Alldrin–Kriegman) or from any other method's normals.
SolveResult solve_monotonic_method(const Observations& obs, const SolveSettings& settings) {
  if (settings.azimuth_from == "isotropy") return solve_monotonic(obs, settings.monotonic);
  if (settings.azimuth_from == "monotonic")
    fail("--azimuth-from: 'monotonic' cannot give its own azimuth (use isotropy or another method)");
  const SolveResult azimuth = find_solve_method(settings.azimuth_from).solve(obs, settings);
  SolveResult result = solve_monotonic(obs, settings.monotonic, azimuth.normals);
  result.parameters["azimuth"] = settings.azimuth_from;
  result.summary.seconds += azimuth.summary.seconds;
  return result;
}

std::vector<SolveMethod>& registry() {
  static std::vector<SolveMethod> methods = {
      {"l2", "Lambertian least squares (Woodham)",
       [](const Observations& obs, const SolveSettings& s) { return solve_lambertian(obs, s.l2); }},
      {"robust", "Lambertian with shadow/highlight rejection and a robust estimator (--estimator)",
       [](const Observations& obs, const SolveSettings& s) { return solve_robust(obs, s.robust); }},
      {"monotonic", "elevation from reflectance monotonicity (Algorithm 1; --azimuth-from)",
       solve_monotonic_method},
      {"bilinear", "bi-polynomial reflectance, k = 1 (Algorithm 2)",
       [](const Observations& obs, const SolveSettings& s) { return solve_bipolynomial_order(obs, s, 1); }},
      {"biquadratic", "bi-polynomial reflectance, k = 2 (Algorithm 2)",
       [](const Observations& obs, const SolveSettings& s) { return solve_bipolynomial_order(obs, s, 2); }},
      {"bicubic", "bi-polynomial reflectance, k = 3 (Algorithm 2)",
       [](const Observations& obs, const SolveSettings& s) { return solve_bipolynomial_order(obs, s, 3); }},
      {"auto", "per pixel, biquadratic or monotonic from evidence in the data",
       [](const Observations& obs, const SolveSettings& s) { return solve_auto(obs, s.automatic); }},
      {"rpca", "low-rank plus sparse decomposition of the stack, inexact ALM (Wu et al. ACCV 2010)",
       [](const Observations& obs, const SolveSettings& s) { return solve_rpca(obs, s.rpca); }},
      {"l1", "per-pixel L1 residual minimisation (Ikehata et al. CVPR 2012)",
       [](const Observations& obs, const SolveSettings& s) { return solve_l1(obs, s.l1); }},
      {"sbl", "per-pixel sparse Bayesian learning (Ikehata et al. CVPR 2012)",
       [](const Observations& obs, const SolveSettings& s) { return solve_sbl(obs, s.sbl); }},
      {"shape-prior",
       "unknown general lighting and camera response, with a depth prior (Algorithm 3; --prior)",
       [](const Observations& obs, const SolveSettings& s) {
         return solve_with_shape_prior(obs, s.shape_prior);
       }},
  };
  return methods;
}

}  // namespace

const std::vector<SolveMethod>& solve_methods() { return registry(); }

std::vector<std::string> solve_method_names() {
  std::vector<std::string> names;
  for (const auto& method : solve_methods()) names.push_back(method.name);
  return names;
}

const SolveMethod& find_solve_method(const std::string& name) {
  for (const auto& method : solve_methods()) {
    if (name == method.name) return method;
  }
  fail("--method: unknown method '{}' (known: {})", name, fmt::join(solve_method_names(), ", "));
}

void register_solve_method(SolveMethod method) {
  if (method.name.empty() || !method.solve)
    fail("register_solve_method: a method needs a name and a function");
  for (const auto& known : solve_methods()) {
    if (known.name == method.name) fail("register_solve_method: '{}' is already a method", method.name);
  }
  registry().push_back(std::move(method));
}

SolvePlan plan_solve(const Observations& observations, const SolveSettings& settings,
                     const ShadowThreshold& data_threshold) {
  find_solve_method(settings.method);
  SolvePlan plan;
  plan.settings = settings;
  plan.threshold = data_threshold;
  if (settings.method != "shape-prior")
    check_light_rank(observations);  // shape-prior estimates its own lighting
  if (settings.shadow_threshold) {
    plan.threshold = ShadowThreshold{};
    plan.threshold.value = *settings.shadow_threshold;
    plan.threshold.source = "flag";
  } else {
    plan.settings.use_data_shadow_threshold(plan.threshold.value);
  }
  plan.warnings = method_warnings(settings.method, observations);
  for (const auto& warning : plan.warnings) logger("host")->warn("{}", warning);
  return plan;
}

SolveResult solve_planned(const Observations& observations, const SolvePlan& plan, bool refit_relighting) {
  const SolveSettings& settings = plan.settings;
  const SolveMethod& method = find_solve_method(settings.method);
  const bool shape_prior = settings.method == "shape-prior";
  const ShadowThreshold& used = plan.threshold;
  // One confidence for every method with known lights, from the same
  // observations and threshold as its solve (shape-prior estimates its lighting).
  ConfidenceOptions confidence;
  confidence.shadow_threshold = settings.drops_shadows() ? std::max(0.0, used.value) : 0.0;
  confidence.threads = settings.threads.value_or(0);
  SolveResult result;
  if (settings.method == "l2") {  // predicts each pixel's error while it has the pixel's lights
    SolveSettings predicting = settings;
    predicting.l2.confidence = confidence;
    result = method.solve(observations, predicting);
  } else {
    result = method.solve(observations, settings);
  }
  result.parameters["shadow_threshold_choice"] = shadow_threshold_choice(used, settings);
  if (!plan.warnings.empty()) result.parameters["warnings"] = plan.warnings;
  // A perspective shape prior sees surfaces whose normals have z < 0; an orthographic camera does not.
  if (!(shape_prior && !settings.shape_prior.intrinsics.empty())) {
    result.summary.findings.push_back(facing_away_fact(clamp_facing_away(result)));
    result.summary.message = result.summary.format_message();
  }
  if (!shape_prior) {
    const cv::Mat error = result.predicted_error.empty()
                              ? predict_normal_error(observations, result, confidence)
                              : result.predicted_error;
    result.confidence = confidence_from_error(error, result.solved, confidence.scale_deg);
    result.predicted_error.release();
    result.parameters["confidence"] = confidence.to_json();
  }
  if (observations.chroma.rows() > 0) result.chroma = chroma_image(observations, result.solved);
  // A per-pixel BRDF is refitted to every lit observation at the answer's
  // normal, for relighting (reflectance/relighting_fit.hpp).
  if (refit_relighting && refits_relighting(result)) {
    RelightingFit fitted = fit_relighting_brdf(observations, result.normals, result.solved,
                                               relighting_fit_options(result, plan), result.coefficients);
    result.coefficients = std::move(fitted.coefficients);
    describe_relighting_fit(fitted, result.reflectance);
  }
  return result;
}

nlohmann::json shadow_threshold_choice(const ShadowThreshold& threshold, const SolveSettings& settings) {
  nlohmann::json choice = threshold.to_json();
  choice["used_by_l2"] = settings.method == "l2" && settings.drops_shadows();
  return choice;
}

bool refits_relighting(const SolveResult& result) {
  return !result.coefficients.empty() && result.reflectance.is_object() &&
         result.reflectance.value("model", "") == "bipolynomial";
}

RelightingFitOptions relighting_fit_options(const SolveResult& result, const SolvePlan& plan) {
  RelightingFitOptions refit;
  refit.order = result.reflectance.at("order").get<int>();
  refit.shadow_threshold = std::max(0.0, plan.threshold.value);
  refit.threads = plan.settings.threads.value_or(0);
  return refit;
}

void describe_relighting_fit(const RelightingFit& fit, nlohmann::json& reflectance) {
  reflectance["fit"] = fit.to_json();
  if (fit.lobe_width > 0) {
    reflectance["specular"] = {{"lobe", "beckmann"}, {"width", fit.lobe_width}, {"term", "S"}};
    reflectance["terms"].push_back("S");
  }
}

namespace {

// 1-3 for the bi-polynomial methods, else 0.
int bipolynomial_method_order(const std::string& method) {
  if (method == "bilinear") return 1;
  if (method == "biquadratic" || method == "auto") return 2;
  if (method == "bicubic") return 3;
  return 0;
}

}  // namespace

bool method_refits_relighting(const std::string& method) { return bipolynomial_method_order(method) > 0; }

int coefficient_terms(const std::string& method) {
  const int order = bipolynomial_method_order(method);
  return order == 0 ? 0 : bipolynomial_term_count(order) + 1;  // and the specular lobe's weight
}

std::size_t solver_working_bytes(const SolveSettings& settings, std::size_t images) {
  return settings.method == "rpca" ? rpca_working_bytes(settings.rpca, images) : 0;
}

std::optional<BiPolynomialOptions> falloff_estimating_options(const SolveSettings& settings) {
  if (settings.method == "monotonic" && settings.azimuth_from != "isotropy" &&
      settings.azimuth_from != "monotonic") {
    SolveSettings azimuth = settings;
    azimuth.method = settings.azimuth_from;
    return falloff_estimating_options(azimuth);
  }
  const BiPolynomialOptions& options =
      settings.method == "auto" ? settings.automatic.bipolynomial : settings.bipolynomial;
  const int order = bipolynomial_method_order(settings.method);
  if (order == 0 || options.falloff) return std::nullopt;
  BiPolynomialOptions estimating = options;
  estimating.order = order;
  return estimating;
}

void use_falloff_estimate(SolveSettings& settings, const FalloffEstimate& estimate) {
  settings.bipolynomial.falloff_estimate = settings.automatic.bipolynomial.falloff_estimate = estimate;
}

SolveFact facing_away_fact(std::size_t count) {
  return {"normals_facing_away", count,
          count == 0 ? std::string{} : fmt::format("{} normals facing away clamped to the horizon", count)};
}

SolveResult solve_with(const Observations& observations, const SolveSettings& settings,
                       const ShadowThreshold& data_threshold) {
  return solve_planned(observations, plan_solve(observations, settings, data_threshold));
}

SolveResult solve_with(const Observations& observations, const SolveSettings& settings) {
  return solve_with(observations, settings,
                    settings.shadow_threshold ? ShadowThreshold{} : estimate_shadow_threshold(observations));
}

SolveWork solve_work(const SolveSettings& settings, const Observations& observations) {
  return solve_work(settings, observations.pixel_count());
}

SolveWork solve_work(const SolveSettings& settings, std::size_t pixels) {
  if (settings.method == "shape-prior") {
    const auto& o = settings.shape_prior.options;
    return {"evaluations", o.refine ? static_cast<std::size_t>(o.max_evaluations) : 0};
  }
  const std::size_t passes = settings.method == "monotonic" && settings.azimuth_from != "isotropy" ? 2 : 1;
  return {"px", pixels * passes};
}

}  // namespace lightstage::pipeline
