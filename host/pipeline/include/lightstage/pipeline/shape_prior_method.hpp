#pragma once
// `--method shape-prior`: loads the depth prior, computes its normals with the
// camera that relates it to the images, and runs the solver (Algorithm 3).

#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/solvers/solve_result.hpp"
#include "lightstage/pipeline/solve_settings.hpp"

namespace lightstage::pipeline {

// Throws InputError naming --prior when it is missing.
SolveResult solve_with_shape_prior(const Observations& observations, const ShapePriorSettings& settings);

}  // namespace lightstage::pipeline
