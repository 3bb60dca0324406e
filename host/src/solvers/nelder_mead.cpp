#include "solvers/nelder_mead.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

namespace lightstage::solvers {
namespace {

NelderMeadResult run(const std::function<double(const Eigen::VectorXd&)>& f, const Eigen::VectorXd& x0,
                     const Eigen::VectorXd& step, int budget, double tolerance) {
  const int n = static_cast<int>(x0.size());
  const double nd = n;
  const double alpha = 1.0, beta = 1.0 + 2.0 / nd, gamma = 0.75 - 1.0 / (2.0 * nd), delta = 1.0 - 1.0 / nd;
  std::vector<Eigen::VectorXd> pts(static_cast<std::size_t>(n) + 1, x0);
  std::vector<double> vals(pts.size());
  int evals = 0;
  auto eval = [&](const Eigen::VectorXd& x) {
    ++evals;
    const double v = f(x);
    return std::isfinite(v) ? v : std::numeric_limits<double>::infinity();
  };
  for (int i = 0; i < n; ++i) pts[static_cast<std::size_t>(i) + 1][i] += step[i];
  for (std::size_t i = 0; i < pts.size(); ++i) vals[i] = eval(pts[i]);
  std::vector<std::size_t> order(pts.size());
  while (evals < budget) {
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return vals[a] < vals[b]; });
    const std::size_t best = order.front(), worst = order.back(), second = order[order.size() - 2];
    if (std::abs(vals[worst] - vals[best]) <= tolerance * (std::abs(vals[best]) + 1e-300)) break;
    Eigen::VectorXd centroid = Eigen::VectorXd::Zero(n);
    for (std::size_t i = 0; i + 1 < order.size(); ++i) centroid += pts[order[i]];
    centroid /= nd;
    const Eigen::VectorXd xr = centroid + alpha * (centroid - pts[worst]);
    const double fr = eval(xr);
    if (fr < vals[best]) {
      const Eigen::VectorXd xe = centroid + beta * (xr - centroid);
      const double fe = eval(xe);
      if (fe < fr) {
        pts[worst] = xe;
        vals[worst] = fe;
      } else {
        pts[worst] = xr;
        vals[worst] = fr;
      }
      continue;
    }
    if (fr < vals[second]) {
      pts[worst] = xr;
      vals[worst] = fr;
      continue;
    }
    const bool outside = fr < vals[worst];
    const Eigen::VectorXd xc = outside ? Eigen::VectorXd(centroid + gamma * (xr - centroid))
                                       : Eigen::VectorXd(centroid + gamma * (pts[worst] - centroid));
    const double fc = eval(xc);
    if (fc < std::min(fr, vals[worst])) {
      pts[worst] = xc;
      vals[worst] = fc;
      continue;
    }
    // Shrink toward the best point.
    for (std::size_t i = 0; i < pts.size(); ++i) {
      if (i == best) continue;
      pts[i] = pts[best] + delta * (pts[i] - pts[best]);
      vals[i] = eval(pts[i]);
    }
  }
  const auto it = std::min_element(vals.begin(), vals.end());
  return {pts[static_cast<std::size_t>(it - vals.begin())], *it, evals};
}

}  // namespace

NelderMeadResult nelder_mead(const std::function<double(const Eigen::VectorXd&)>& f,
                             const Eigen::VectorXd& x0, const Eigen::VectorXd& step, int max_evaluations,
                             double tolerance) {
  NelderMeadResult first = run(f, x0, step, max_evaluations / 2, tolerance);
  const int left = max_evaluations - first.evaluations;
  if (left <= static_cast<int>(x0.size()) + 1) return first;
  NelderMeadResult second = run(f, first.x, 0.25 * step, left, tolerance);
  second.evaluations += first.evaluations;
  if (second.value > first.value) {
    first.evaluations = second.evaluations;
    return first;
  }
  return second;
}

}  // namespace lightstage::solvers
