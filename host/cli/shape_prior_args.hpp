#pragma once
// `solve --method shape-prior`: its flags (the depth prior, the camera that
// relates the prior to the images, the solver's options) and the method
// function of the --method table (methods.hpp).

#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/solvers/shape_prior.hpp"

#include <CLI/CLI.hpp>

#include <string>

namespace lightstage::cli {

struct ShapePriorArgs {
  ShapePriorOptions options;
  std::string prior;        // --prior: depth PNG, PFM or PLY
  std::string intrinsics;   // --intrinsics K.txt: perspective camera
  double pixel_mm = 1.0;    // --pixel-mm: orthographic pixel size in the prior's unit
  double prior_radius = 0;  // --prior-radius: plane-PCA radius; 0 = three pixel footprints
  double png_scale = 1.0;   // --prior-png-scale: depth unit per DN of a 16-bit PNG
};

void add_shape_prior_flags(CLI::App& sub, ShapePriorArgs& args);

// Loads the prior, computes its normals and runs the solver. Throws
// InputError naming the flag when --prior is missing.
SolveResult solve_shape_prior_method(const Observations& observations, const ShapePriorArgs& args);

}  // namespace lightstage::cli
