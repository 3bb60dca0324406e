#pragma once
// Nelder–Mead simplex minimisation with the dimension-adaptive coefficients
// of Gao & Han (2012), which keep it useful in the 27–48 dimensions of the
// shape-prior ambiguity.

#include <Eigen/Core>

#include <functional>

namespace lightstage::solvers {

struct NelderMeadResult {
  Eigen::VectorXd x;
  double value = 0;
  int evaluations = 0;
};

// Minimises f from x0; the initial simplex steps each coordinate by step[i].
// Stops after max_evaluations or when the simplex's values agree to
// tolerance (relative). Restarts once from the best point, which un-sticks
// a collapsed simplex.
NelderMeadResult nelder_mead(const std::function<double(const Eigen::VectorXd&)>& f,
                             const Eigen::VectorXd& x0, const Eigen::VectorXd& step, int max_evaluations,
                             double tolerance = 1e-10);

}  // namespace lightstage::solvers
