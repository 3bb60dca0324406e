#pragma once
// `solve --method shape-prior`: its flags (the depth prior, the camera that
// relates the prior to the images, the solver's options).

#include "lightstage/pipeline/solve_settings.hpp"

#include <CLI/CLI.hpp>

namespace lightstage::cli {

void add_shape_prior_flags(CLI::App& sub, pipeline::ShapePriorSettings& args);

}  // namespace lightstage::cli
