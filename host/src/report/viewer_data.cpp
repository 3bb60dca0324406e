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

// Every stride-th row and column.
cv::Mat subsample(const cv::Mat& image, int stride) {
  if (stride <= 1 || image.empty()) return image;
  cv::Mat out((image.rows + stride - 1) / stride, (image.cols + stride - 1) / stride, image.type());
  for (int y = 0; y < out.rows; ++y) {
    for (int x = 0; x < out.cols; ++x) {
      std::memcpy(out.ptr(y, x), image.ptr(y * stride, x * stride), image.elemSize());
    }
  }
  return out;
}

}  // namespace

SurfaceModel load_surface_model(const io::SolveFolder& folder, int max_pixels,
                                std::vector<std::string>& notes) {
  if (max_pixels < 1) fail("report: viewer pixel budget must be ≥ 1, got {}", max_pixels);
  const RelightModel relight_model = lightstage::relight_model(folder);
  const nlohmann::json& summary = folder.summary;
  SurfaceModel model;
  model.source_size = relight_model.normals.size();
  model.display_scale = folder.chroma.empty() ? folder.albedo_png_scale : folder.albedo_rgb_png_scale;
  if (folder.albedo.empty())
    notes.push_back(
        "No albedo.pfm or albedo.png in the result folder: the viewer (like `lightstage relight`) uses "
        "albedo 1.");
  else if (folder.albedo_from_png)
    notes.push_back(
        "No albedo.pfm in the result folder: the viewer uses albedo.png (16-bit, clipped at its scale).");
  if (relight_model.order > 0) {
    model.kind = ShadingKind::kBiPolynomial;
    model.order = relight_model.order;
    model.lobe_width = relight_model.lobe_width;
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
  model.normals = subsample(relight_model.normals, model.stride);
  model.valid = subsample(relight_model.solved, model.stride);
  model.albedo = subsample(relight_model.albedo, model.stride);
  model.chroma = subsample(relight_model.chroma, model.stride);
  if (model.kind == ShadingKind::kBiPolynomial)
    model.coefficients = subsample(relight_model.coefficients, model.stride);
  return model;
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
