#pragma once
// A solver's results on disk, in one output folder:
//   normal.png      16-bit normal map (project encoding, zero where not solved)
//   normal_vis.png  8-bit picture of the normals
//   albedo.png      16-bit grey, value = round(min(albedo / scale, 1) · 65535), where
//                   scale = the 99.5th percentile of the solved albedo (recorded in summary.json)
//   albedo.pfm      float albedo (0 where not solved)
//   residual.pfm    float RMS residual of the fit (0 where not solved)
//   summary.json    method, parameters, summary fields, time, input, software version

#include "lightstage/host/solvers/solve_result.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>

namespace lightstage::io {

// Writes the files above into `dir` (created if needed), each atomically.
// `input` is recorded as the input folder; keys of `extra` (an object) are
// added to summary.json. Returns the JSON written to summary.json.
nlohmann::json write_solve_outputs(const std::filesystem::path& dir, const SolveResult& result,
                                   const std::filesystem::path& input,
                                   const nlohmann::json& extra = nlohmann::json::object());

// The albedo scale used for albedo.png: the 99.5th percentile of the albedo
// over solved pixels, or 1 when there are none (or it is not positive).
double albedo_png_scale(const SolveResult& result);

}  // namespace lightstage::io
