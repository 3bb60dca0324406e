#pragma once
// What the report's relighting viewer relights, and how: the shading
// definition shared by the viewer's JavaScript (host/src/report/web/shading.js)
// and the C++ reference here. Camera frame: x right, y up, z toward the
// camera; viewer v = (0, 0, 1); light directions point from the object to the
// light (unit, distant light of unit intensity).
//
//   lambertian:    value = albedo · max(0, n·l)
//   bipolynomial:  value = max(0, ρ(n·h, l·h)) · max(0, n·l), h = normalise(l + v),
//                  ρ the per-pixel model of reflectance/bipolynomial_model.hpp
// — the definition of `lightstage relight` (reflectance/relight.hpp), whose
// loader reads the files here too.
//
// The page shows value / display_scale as a linear grey (0 → black, ≥ 1 → white);
// a colour result (SurfaceModel::chroma) in colour as relight_colour renders it.

#include "lightstage/common/geometry.hpp"
#include "lightstage/host/io/solve_folder_rows.hpp"
#include "lightstage/host/io/solve_output.hpp"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace lightstage::report {

enum class ShadingKind { kLambertian, kBiPolynomial };

struct SurfaceModel {
  cv::Mat normals;       // CV_32FC3 (x, y, z), unit where valid: decoded from normal.png
  cv::Mat valid;         // CV_8UC1, 255 where normal.png holds a normal
  cv::Mat albedo;        // CV_32FC1: albedo.pfm (1 when there is none, as relight does)
  cv::Mat chroma;        // CV_32FC3 (b, g, r) of a colour result, else empty (relight.hpp)
  cv::Mat coefficients;  // CV_32FC(terms) for kBiPolynomial (summary.json files.brdf), C_ij at i·(k+1)+j
  ShadingKind kind = ShadingKind::kLambertian;
  int order = 0;          // bi-polynomial order k (1..3); 0 for Lambertian
  double lobe_width = 0;  // > 0: the last coefficient weighs a specular lobe of this width
  double display_scale =
      1.0;         // the value shown as white (summary.json albedo_png_scale; colour: albedo_rgb_png_scale)
  int stride = 1;  // every stride-th pixel of the result, in x and y
  cv::Size source_size;  // the result's size before striding
};

// The viewer's model of a solve folder (io/solve_output.hpp): its normals,
// albedo and, when a bi-polynomial model was fitted, its coefficient maps — the
// model `lightstage relight` renders (relight_model), so the two agree. Results
// larger than `max_pixels` are subsampled with an integer stride (recorded in the
// model). Gathered a band of rows at a time, so that a result larger than
// memory never is held whole; notes on what was used or left out are appended
// to `notes`.
class SurfaceModelBuilder {
 public:
  SurfaceModelBuilder(const io::SolveFolderRows& folder, int max_pixels, std::vector<std::string>& notes);
  // The folder's next band (SolveFolderRows::read), whose first row is `y0`.
  void add(const io::SolveFolder& band, int y0);
  SurfaceModel finish();

 private:
  SurfaceModel model_;
  int rows_added_ = 0;
};

// The builder given every row of `folder`, `band_rows` at a time.
SurfaceModel load_surface_model(io::SolveFolderRows& folder, int max_pixels, std::vector<std::string>& notes,
                                int band_rows = 256);

// The value of pixel (x, y) under `light` (normalised here); 0 where not valid.
double shade(const SurfaceModel& model, int x, int y, const Vec3& light);

// Every pixel: CV_32FC1, 0 where not valid.
cv::Mat relight(const SurfaceModel& model, const Vec3& light);
// Every pixel in colour: CV_32FC3 (BGR), 0 where not valid; lightstage::relight_colour.
cv::Mat relight_colour(const SurfaceModel& model, const Vec3& light);

// The page's embedded data (viewer.js reads it): `meta` (width, height,
// encoding, planes, model, display, lights, light) and the base64 of the
// zlib-deflated planes (little-endian float32 albedo, coefficients and, for
// a colour result, chroma in r g b order; then uint16 normals in the
// normal.png encoding).
struct ViewerPayload {
  nlohmann::json meta;
  std::string data_base64;
};
ViewerPayload encode_viewer_payload(const SurfaceModel& model, const std::vector<Vec3>& capture_lights,
                                    const Vec3& initial_light);

}  // namespace lightstage::report
