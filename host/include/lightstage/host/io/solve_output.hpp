#pragma once
// A solver's results on disk, in one output folder (a "solve folder"), written
// and read back only here:
//   normal.png      16-bit normal map (project encoding, zero where not solved)
//   normal_vis.png  8-bit picture of the normals
//   albedo.png      16-bit grey, value = round(min(albedo / scale, 1) · 65535), where
//                   scale = the 99.5th percentile of the solved albedo (recorded in summary.json)
//   albedo.pfm      float albedo (0 where not solved)
//   residual.pfm    float RMS residual of the fit (0 where not solved)
//   normal.exr      float normals, channels R G B = x y z (0 where not solved)
//   albedo.exr      float albedo, channel Y
//   albedo_rgb.pfm  colour stacks: float colour albedo = albedo · chroma (radiometry.hpp),
//                   listed in summary.json files.albedo_colour_float (read only then)
//   albedo_rgb.exr  colour stacks: the same, channels R G B
//   albedo_rgb.png  colour stacks: 16-bit RGB, white at summary.json albedo_rgb_png_scale
//                   (the 99.5th percentile of every channel, so saturated colours keep their hue)
//   summary.json    method, parameters, summary fields, time, input, software version
//   confidence.pfm  when the method gives one: float confidence in [0, 1]
//                   (normal_confidence.hpp: 1 / (1 + predicted error / scale))
//   method_map.png  when the method chooses per pixel (auto): one colour per choice,
//                   legend and pixel counts in summary.json method_map
//   brdf_*.pfm      when the method fits a per-pixel reflectance: one float map per
//                   coefficient, listed in summary.json files.brdf, described by "reflectance"

#include "lightstage/host/solvers/solve_result.hpp"

#include <nlohmann/json.hpp>

#include <opencv2/core.hpp>

#include <filesystem>

namespace lightstage::io {

// Writes the files above into `dir` (created if needed), each atomically
// (through SolveOutputWriter, solve_output_writer.hpp, as one band).
// `input` is recorded as the input folder; keys of `extra` (an object) are
// added to summary.json. Returns the JSON written to summary.json.
nlohmann::json write_solve_outputs(const std::filesystem::path& dir, const SolveResult& result,
                                   const std::filesystem::path& input,
                                   const nlohmann::json& extra = nlohmann::json::object());

// The colour albedo: albedo (CV_32FC1) · chroma (CV_32FC3, BGR) per channel.
cv::Mat times_chroma(const cv::Mat& albedo, const cv::Mat& chroma);

// A solve folder read back. Every reader of solve results (report, integrate,
// relight, reflectance, the demo) goes through this, so the files are decoded
// one way everywhere.
struct SolveFolder {
  std::filesystem::path dir;
  nlohmann::json summary = nlohmann::json::object();  // summary.json ({} when there is none)
  cv::Mat normals;  // CV_32FC3 (normal.exr, else normal.png), zero where not solved
  cv::Mat solved;   // CV_8UC1, 255 where normal.png holds a normal
  // CV_32FC1, the solver's albedo: albedo.pfm, else albedo.png times the
  // albedo_png_scale of summary.json; empty when the folder has neither.
  cv::Mat albedo;
  bool albedo_from_png = false;  // albedo came from the 16-bit PNG (quantised, clipped at the scale)
  // CV_32FC3 (b, g, r) chroma: albedo_rgb.pfm / albedo (neutral where the albedo
  // is 0); empty for grey results.
  cv::Mat chroma;
  double albedo_rgb_png_scale = 1;  // summary.json's, for colour results
  double albedo_png_scale = 1;      // summary.json's, 1 when absent or not positive
  cv::Mat residual;                 // CV_32FC1 or empty
  cv::Mat confidence;               // CV_32FC1 or empty
  // The per-pixel reflectance model: CV_32FC(k) from files.brdf, with order > 0 for a
  // bi-polynomial (k + 1 channels with reflectance.specular); empty (order 0)
  // when the method fitted none.
  cv::Mat coefficients;
  int reflectance_order = 0;
  double lobe_width = 0;  // > 0: the coefficients' last channel weighs a specular lobe of this width
  nlohmann::json reflectance = nullptr;  // summary.json "reflectance"

  // albedo · chroma (CV_32FC3, BGR) for colour results, else the grey albedo.
  cv::Mat colour_albedo() const;
  // colour_albedo() over its PNG's scale, clipped to [0, 1]: what albedo_rgb.png
  // or albedo.png shows (for mesh colours and pictures). Empty when there is
  // no albedo.
  cv::Mat display_albedo() const;
  std::string method() const { return summary.value("method", std::string()); }
};

// Reads `dir` (normal.png required; the rest when present). Throws InputError
// naming the file when one does not decode or does not match normal.png's size,
// or when summary.json is not a JSON object.
SolveFolder read_solve_folder(const std::filesystem::path& dir);

}  // namespace lightstage::io
