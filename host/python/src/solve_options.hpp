#pragma once
// solve()'s keyword options onto pipeline::SolveSettings: the solve flags of
// the CLI with underscores (shadow_threshold for --shadow-threshold). An
// unknown name raises TypeError listing the known ones.

#include "lightstage/pipeline/solve_settings.hpp"

#include <pybind11/pybind11.h>

namespace lightstage::python {

void apply_solve_options(pipeline::SolveSettings& settings, const pybind11::kwargs& options);

}  // namespace lightstage::python
