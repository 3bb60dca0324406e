#include "lightstage/host/report/viewer_data.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/reflectance/bipolynomial_model.hpp"
#include "lightstage/host/reflectance/relight.hpp"
#include "report/html.hpp"

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>

namespace lightstage::report {

namespace {

static_assert(std::endian::native == std::endian::little, "the viewer payload is written little-endian");

// Every stride-th column of the rows of `band` (whose first row is y0) that are
// multiples of the stride, appended to `out` from its row y0 / stride on.
void add_subsampled(const cv::Mat& band, int y0, int stride, cv::Mat& out) {
  for (int r = 0; r < band.rows; ++r) {
    const int y = y0 + r;
    if (y % stride != 0) continue;
    auto* dst = out.ptr(y / stride);
    for (int x = 0; x < out.cols; ++x)
      std::memcpy(dst + x * band.elemSize(), band.ptr(r, x * stride), band.elemSize());
  }
}

}  // namespace

SurfaceModelBuilder::SurfaceModelBuilder(const io::SolveFolderRows& folder, int max_pixels,
                                         std::vector<std::string>& notes) {
  if (max_pixels < 1) fail("report: viewer pixel budget must be ≥ 1, got {}", max_pixels);
  const io::SolveFolder& facts = folder.facts();
  const nlohmann::json& summary = facts.summary;
  SurfaceModel& model = model_;
  model.source_size = folder.size();
  model.display_scale = folder.has_chroma() ? facts.albedo_rgb_png_scale : facts.albedo_png_scale;
  if (!folder.has_albedo())
    notes.push_back(
        "No albedo.pfm or albedo.png in the result folder: the viewer (like `lightstage relight`) uses "
        "albedo 1.");
  else if (facts.albedo_from_png)
    notes.push_back(
        "No albedo.pfm in the result folder: the viewer uses albedo.png (16-bit, clipped at its scale).");
  if (facts.reflectance_order > 0) {
    model.kind = ShadingKind::kBiPolynomial;
    model.order = facts.reflectance_order;
    model.lobe_width = facts.lobe_width;
  } else if (const auto it = summary.find("reflectance");
             it != summary.end() && it->is_object() && it->value("model", "") == "bipolynomial") {
    notes.push_back(
        "The solver fitted a bi-polynomial model but summary.json lists no coefficient maps (files.brdf): "
        "the "
        "viewer shades with albedo · max(0, n·l).");
  }

  const double pixels = static_cast<double>(model.source_size.area());
  model.stride = std::max(1, static_cast<int>(std::ceil(std::sqrt(pixels / max_pixels))));
  if (model.stride > 1) {
    notes.push_back(
        fmt::format("The viewer shows every {}th pixel of the {}x{} result (page size budget {} pixels).",
                    model.stride, model.source_size.width, model.source_size.height, max_pixels));
  }
  const cv::Size size((model.source_size.width + model.stride - 1) / model.stride,
                      (model.source_size.height + model.stride - 1) / model.stride);
  model.normals = cv::Mat(size, CV_32FC3);
  model.valid = cv::Mat(size, CV_8UC1);
  model.albedo = cv::Mat(size, CV_32FC1);
  if (folder.has_chroma()) model.chroma = cv::Mat(size, CV_32FC3);
  if (model.kind == ShadingKind::kBiPolynomial)
    model.coefficients = cv::Mat(size, CV_32FC(relighting_term_count(model.order, model.lobe_width)));
}

void SurfaceModelBuilder::add(const io::SolveFolder& band, int y0) {
  if (y0 != rows_added_ || y0 + band.normals.rows > model_.source_size.height)
    fail("report: viewer rows from {} given after {} of {}", y0, rows_added_, model_.source_size.height);
  const RelightModel rows = lightstage::relight_model(band);
  const int stride = model_.stride;
  add_subsampled(rows.normals, y0, stride, model_.normals);
  add_subsampled(rows.solved, y0, stride, model_.valid);
  add_subsampled(rows.albedo, y0, stride, model_.albedo);
  if (!model_.chroma.empty()) add_subsampled(rows.chroma, y0, stride, model_.chroma);
  if (model_.kind == ShadingKind::kBiPolynomial)
    add_subsampled(rows.coefficients, y0, stride, model_.coefficients);
  rows_added_ += band.normals.rows;
}

SurfaceModel SurfaceModelBuilder::finish() {
  if (rows_added_ != model_.source_size.height)
    fail("report: the viewer was given {} of the result's {} rows", rows_added_, model_.source_size.height);
  return std::move(model_);
}

SurfaceModel load_surface_model(io::SolveFolderRows& folder, int max_pixels, std::vector<std::string>& notes,
                                int band_rows) {
  SurfaceModelBuilder builder(folder, max_pixels, notes);
  const int height = folder.size().height, step = std::max(band_rows, 1);
  for (int y = 0; y < height; y += step) builder.add(folder.read(y, std::min(step, height - y)), y);
  return builder.finish();
}

namespace {

// The model as relight.hpp's, at the viewer's stride (it relights the same way).
RelightModel as_relight_model(const SurfaceModel& model) {
  RelightModel m;
  m.normals = model.normals;
  m.solved = model.valid;
  m.albedo = model.albedo;
  m.chroma = model.chroma;
  if (model.kind == ShadingKind::kBiPolynomial) {
    m.coefficients = model.coefficients;
    m.order = model.order;
    m.lobe_width = model.lobe_width;
  }
  return m;
}

}  // namespace

double shade(const SurfaceModel& model, int x, int y, const Vec3& light) {
  if (model.valid.at<std::uint8_t>(y, x) == 0) return 0;
  const Vec3 l = light.normalized();
  const cv::Vec3f nf = model.normals.at<cv::Vec3f>(y, x);
  const Vec3 n(nf[0], nf[1], nf[2]);
  const double nl = n.dot(l);
  if (!(nl > 0)) return 0;
  if (model.kind == ShadingKind::kBiPolynomial) {
    const int terms = relighting_term_count(model.order, model.lobe_width);
    const auto* c = model.coefficients.ptr<float>(y) + static_cast<std::ptrdiff_t>(x) * terms;
    const Vec3 h = (l + Vec3::UnitZ()).normalized();
    return evaluate_relighting_brdf(model.order, model.lobe_width, c, n.dot(h), l.dot(h)) * nl;
  }
  return std::max(0.0f, model.albedo.at<float>(y, x)) * nl;
}

namespace {

// The coefficient maps must hold what the model reads for every pixel.
void check_coefficients(const SurfaceModel& model) {
  if (model.kind != ShadingKind::kBiPolynomial) return;
  const int terms = relighting_term_count(model.order, model.lobe_width);
  if (model.coefficients.type() != CV_32FC(terms) || model.coefficients.size() != model.normals.size())
    fail("report: the bi-polynomial viewer model needs {} coefficient maps of the normals' size", terms);
}

}  // namespace

cv::Mat relight(const SurfaceModel& model, const Vec3& light) {
  check_coefficients(model);
  cv::Mat out(model.normals.size(), CV_32FC1, cv::Scalar(0));
  for (int y = 0; y < out.rows; ++y)
    for (int x = 0; x < out.cols; ++x) out.at<float>(y, x) = static_cast<float>(shade(model, x, y, light));
  return out;
}

cv::Mat relight_colour(const SurfaceModel& model, const Vec3& light) {
  check_coefficients(model);
  return lightstage::relight_colour(as_relight_model(model), light);
}

ViewerPayload encode_viewer_payload(const SurfaceModel& model, const std::vector<Vec3>& capture_lights,
                                    const Vec3& initial_light) {
  check_coefficients(model);
  const int width = model.normals.cols, height = model.normals.rows;
  const auto count = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  std::vector<std::uint8_t> bytes;
  nlohmann::json planes = nlohmann::json::array();
  const auto append = [&](const char* name, const char* type, int components, const void* data,
                          std::size_t size) {
    planes.push_back({{"name", name},
                      {"type", type},
                      {"components", components},
                      {"offset", bytes.size()},
                      {"bytes", size}});
    const auto* begin = static_cast<const std::uint8_t*>(data);
    bytes.insert(bytes.end(), begin, begin + size);
  };
  const cv::Mat albedo = model.albedo.isContinuous() ? model.albedo : model.albedo.clone();
  append("albedo", "float32", 1, albedo.data, count * sizeof(float));
  if (model.kind == ShadingKind::kBiPolynomial) {
    const cv::Mat c = model.coefficients.isContinuous() ? model.coefficients : model.coefficients.clone();
    append("coefficients", "float32", c.channels(), c.data,
           count * sizeof(float) * static_cast<std::size_t>(c.channels()));
  }
  cv::Mat chroma_rgb;
  if (!model.chroma.empty()) {
    if (model.chroma.type() != CV_32FC3 || model.chroma.size() != model.normals.size())
      fail("report: the viewer's chroma must be a colour map of the normals' size");
    cv::cvtColor(model.chroma, chroma_rgb, cv::COLOR_BGR2RGB);
    append("chroma", "float32", 3, chroma_rgb.data, count * 3 * sizeof(float));
  }
  // Normals re-encoded as normal.png encodes them (round((n+1)/2·65535), x y z order).
  cv::Mat encoded(model.normals.size(), CV_16UC3, cv::Scalar::all(0));
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      if (model.valid.at<std::uint8_t>(y, x) == 0) continue;
      const cv::Vec3f n = model.normals.at<cv::Vec3f>(y, x);
      auto& e = encoded.at<cv::Vec3w>(y, x);
      for (int c = 0; c < 3; ++c)
        e[c] = static_cast<std::uint16_t>(std::clamp(std::round((n[c] + 1.0) / 2.0 * 65535.0), 0.0, 65535.0));
      if (e[0] == 0 && e[1] == 0 && e[2] == 0) e[0] = 1;
    }
  }
  append("normals", "uint16", 3, encoded.data, count * 3 * sizeof(std::uint16_t));

  nlohmann::json lights = nlohmann::json::array();
  for (const Vec3& l : capture_lights) {
    const Vec3 n = l.normalized();
    lights.push_back({n.x(), n.y(), n.z()});
  }
  const Vec3 initial = initial_light.normalized();
  ViewerPayload payload;
  payload.meta = {
      {"width", width},
      {"height", height},
      {"encoding", "deflate"},
      {"planes", planes},
      {"model", model.kind == ShadingKind::kBiPolynomial ? nlohmann::json{{"kind", "bipolynomial"},
                                                                          {"order", model.order},
                                                                          {"lobe_width", model.lobe_width}}
                                                         : nlohmann::json{{"kind", "lambertian"}}},
      {"display", {{"scale", model.display_scale}, {"gamma", "linear"}}},
      {"colour", !model.chroma.empty()},
      {"stride", model.stride},
      {"source_size", {model.source_size.width, model.source_size.height}},
      {"lights", lights},
      {"light", {initial.x(), initial.y(), initial.z()}}};
  payload.data_base64 = base64(zlib_compress(bytes));
  return payload;
}

}  // namespace lightstage::report
