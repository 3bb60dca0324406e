#pragma once
// Simulating a stack folder: the rig's LEDs over a sim scene, written with its
// ground truth and manifest (docs/stack-format.md).

#include "lightstage/sim/natural_lighting.hpp"
#include "lightstage/sim/simulate.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>

namespace lightstage::pipeline {

// Simulates the rig in `rig_path` under `options` and writes the stack into
// `out`. Returns a JSON summary of what was written. `on_frames` (optional)
// hears of every frame rendered (sim::simulate_stack). Throws InputError,
// before rendering, when `out` exists and is not empty, unless `overwrite`
// (--force): then the files it writes replace theirs, and nothing else is removed.
nlohmann::json simulate_to_folder(const std::filesystem::path& rig_path, const sim::SimulateOptions& options,
                                  const std::filesystem::path& out, const sim::FrameProgress& on_frames = {},
                                  bool overwrite = false);

// Natural lighting instead of the dome's LEDs (sim/natural_capture.hpp), for
// `solve --method shape-prior`.
struct NaturalSimulation {
  std::string environment = "area-lights";            // area-lights or sh
  std::string response = "random";                    // random, fixed or linear (sim::parse_response_mode)
  int frames = sim::NaturalLightingOptions{}.images;  // images, each under its own lighting
  int prior_beta = 3;                                 // prior.pfm degraded as Fig. 4.5's level 1..5; 0 = none
};

// Renders the scene under natural lighting and writes the stack, a degraded
// depth prior and, for a pinhole camera, its intrinsics (K.txt). The summary
// names them under "shape_prior_flags". `out` as for simulate_to_folder.
nlohmann::json simulate_natural_to_folder(const std::filesystem::path& rig_path,
                                          const sim::SimulateOptions& options,
                                          const NaturalSimulation& natural, const std::filesystem::path& out,
                                          const sim::FrameProgress& on_frames = {}, bool overwrite = false);

}  // namespace lightstage::pipeline
