#pragma once
// Relighting from a solver's output folder: normals plus a per-pixel BRDF
// (the bi-polynomial coefficients a bi-polynomial or auto solve writes) or,
// for methods without one, the Lambertian albedo. A rendered value is
//   ρ(n·h, l·h) · max(n·l, 0)    (ρ clamped to ≥ 0; plus the specular lobe
//                                 when the solve fitted one)
// in the stack's units (linear, at unit light intensity). A colour result
// (io::SolveFolder::chroma) relights in colour: per channel c
//   max(0, chroma_c · ρ_polynomial + ρ_lobe) · max(n·l, 0)
// (the Lambertian fallback: chroma_c · albedo · max(n·l, 0)), whose BT.601
// grey is the grey value above wherever it is not clamped.

#include "lightstage/common/geometry.hpp"
#include "lightstage/host/io/solve_output.hpp"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <filesystem>

namespace lightstage {

struct RelightModel {
  cv::Mat normals;        // CV_32FC3
  cv::Mat solved;         // CV_8UC1
  cv::Mat albedo;         // CV_32FC1 (Lambertian fallback)
  cv::Mat coefficients;   // CV_32FC(k), CV_32FC(k + 1) with the lobe, or empty
  int order = 0;          // bi-polynomial order, 0 = Lambertian albedo
  double lobe_width = 0;  // > 0: the last coefficient weighs a specular lobe (bipolynomial_model.hpp)
  cv::Mat chroma;         // CV_32FC3 (b, g, r) of a colour result, else empty
};

// The model of a solve folder (io/solve_output.hpp): its normals, albedo (1
// where the folder has none) and bi-polynomial coefficient maps.
RelightModel relight_model(const io::SolveFolder& folder);
// The same, read from a `solve` output folder. Errors name the file.
RelightModel load_relight_model(const std::filesystem::path& result_dir);

// CV_32FC1 image under one distant light `light` (object -> light, normalised here).
cv::Mat relight(const RelightModel& model, const Vec3& light, const Vec3& view = Vec3::UnitZ());
// CV_32FC3 (BGR) image in colour as above; the grey in all three channels when
// the model has no chroma.
cv::Mat relight_colour(const RelightModel& model, const Vec3& light, const Vec3& view = Vec3::UnitZ());

// `count` lights on a ring at `elevation_deg` above the image plane, for a
// turntable-of-light animation.
std::vector<Vec3> turntable_lights(int count, double elevation_deg);

}  // namespace lightstage
