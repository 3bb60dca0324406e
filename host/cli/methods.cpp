#include "methods.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/solvers/auto.hpp"
#include "lightstage/host/solvers/bipolynomial.hpp"
#include "lightstage/host/solvers/lambertian.hpp"
#include "lightstage/host/solvers/monotonic.hpp"
#include "lightstage/host/solvers/robust.hpp"

#include <fmt/format.h>

namespace lightstage::cli {
namespace {

SolveResult solve_l2(const Observations& obs, const SolveArgs& args) {
  return solve_lambertian(obs, args.l2);
}

SolveResult solve_robust_method(const Observations& obs, const SolveArgs& args) {
  return solve_robust(obs, args.robust);
}

SolveResult solve_bipolynomial_order(const Observations& obs, const SolveArgs& args, int order) {
  BiPolynomialOptions options = args.bipolynomial;
  options.order = order;
  return solve_bipolynomial(obs, options);
}
SolveResult solve_bilinear(const Observations& obs, const SolveArgs& args) {
  return solve_bipolynomial_order(obs, args, 1);
}
SolveResult solve_biquadratic(const Observations& obs, const SolveArgs& args) {
  return solve_bipolynomial_order(obs, args, 2);
}
SolveResult solve_bicubic(const Observations& obs, const SolveArgs& args) {
  return solve_bipolynomial_order(obs, args, 3);
}

// --azimuth-from isotropy (Alldrin–Kriegman) or any other method's normals.
SolveResult solve_monotonic_method(const Observations& obs, const SolveArgs& args) {
  if (args.azimuth_from == "isotropy") return solve_monotonic(obs, args.monotonic);
  if (args.azimuth_from == "monotonic")
    fail("--azimuth-from: 'monotonic' cannot give its own azimuth (use isotropy or another method)");
  const SolveResult azimuth = find_solve_method(args.azimuth_from).solve(obs, args);
  SolveResult result = solve_monotonic(obs, args.monotonic, azimuth.normals);
  result.parameters["azimuth"] = args.azimuth_from;
  result.summary.seconds += azimuth.summary.seconds;
  return result;
}

SolveResult solve_shape_prior_entry(const Observations& obs, const SolveArgs& args) {
  return solve_shape_prior_method(obs, args.shape_prior);
}

SolveResult solve_auto_method(const Observations& obs, const SolveArgs& args) {
  return solve_auto(obs, args.automatic);
}

}  // namespace

const std::vector<SolveMethod>& solve_methods() {
  static const std::vector<SolveMethod> table = {
      {"l2", "Lambertian least squares (Woodham)", solve_l2},
      {"robust", "Lambertian with shadow/highlight rejection and a robust estimator (--estimator)",
       solve_robust_method},
      {"monotonic", "elevation from reflectance monotonicity (Algorithm 1; --azimuth-from)",
       solve_monotonic_method},
      {"bilinear", "bi-polynomial reflectance, k = 1 (Algorithm 2)", solve_bilinear},
      {"biquadratic", "bi-polynomial reflectance, k = 2 (Algorithm 2)", solve_biquadratic},
      {"bicubic", "bi-polynomial reflectance, k = 3 (Algorithm 2)", solve_bicubic},
      {"auto", "per pixel, biquadratic or monotonic from evidence in the data", solve_auto_method},
      {"shape-prior",
       "unknown general lighting and camera response, with a depth prior (Algorithm 3; --prior)",
       solve_shape_prior_entry},
  };
  return table;
}

std::vector<std::string> solve_method_names() {
  std::vector<std::string> names;
  for (const auto& method : solve_methods()) names.emplace_back(method.name);
  return names;
}

const SolveMethod& find_solve_method(const std::string& name) {
  for (const auto& method : solve_methods()) {
    if (name == method.name) return method;
  }
  fail("--method: unknown method '{}' (known: {})", name, fmt::join(solve_method_names(), ", "));
}

}  // namespace lightstage::cli
