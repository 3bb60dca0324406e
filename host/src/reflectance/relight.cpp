#include "lightstage/host/reflectance/relight.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/reflectance/bipolynomial_model.hpp"

#include <algorithm>
#include <vector>

namespace lightstage {

RelightModel relight_model(const io::SolveFolder& folder) {
  RelightModel model;
  model.normals = folder.normals;
  model.solved = folder.solved;
  model.albedo =
      folder.albedo.empty() ? cv::Mat(folder.normals.size(), CV_32FC1, cv::Scalar::all(1)) : folder.albedo;
  model.coefficients = folder.coefficients;
  model.order = folder.reflectance_order;
  model.lobe_width = folder.lobe_width;
  model.chroma = folder.chroma;
  return model;
}

RelightModel load_relight_model(const std::filesystem::path& dir) {
  if (!std::filesystem::is_directory(dir))
    fail("--input {}: not a folder (expected a `solve` output folder)", dir.string());
  return relight_model(io::read_solve_folder(dir));
}

namespace {

// Calls shade(x, y, parts, n·l) for every solved pixel the light reaches, with
// the model's ρ split as evaluate_relighting_parts splits it (the Lambertian
// fallback's albedo is all polynomial).
template <typename Shade>
void for_each_lit_pixel(const RelightModel& model, const Vec3& light_in, const Vec3& view, Shade&& shade) {
  if (!(light_in.norm() > 0)) fail("--light: a light direction must not be zero");
  const Vec3 l = light_in.normalized();
  const Vec3 h = (l + view).normalized();
  const int k = model.order > 0 ? relighting_term_count(model.order, model.lobe_width) : 0;
  if (k > 0 && (model.coefficients.type() != CV_32FC(k) || model.coefficients.size() != model.normals.size()))
    fail("relight: the bi-polynomial model needs {} coefficient maps of the normals' size", k);
  if (!model.chroma.empty() &&
      (model.chroma.type() != CV_32FC3 || model.chroma.size() != model.normals.size()))
    fail("relight: the chroma must be a colour map of the normals' size");
  for (int y = 0; y < model.normals.rows; ++y) {
    for (int x = 0; x < model.normals.cols; ++x) {
      if (model.solved.at<std::uint8_t>(y, x) == 0) continue;
      const cv::Vec3f v = model.normals.at<cv::Vec3f>(y, x);
      const Vec3 n(v[0], v[1], v[2]);
      const double n_dot_l = n.dot(l);
      if (n_dot_l <= 0) continue;
      RelightingBrdfParts parts;
      if (k > 0) {
        const float* row = model.coefficients.ptr<float>(y) + static_cast<std::ptrdiff_t>(x) * k;
        parts = evaluate_relighting_parts(model.order, model.lobe_width, row, n.dot(h), l.dot(h));
      } else {
        parts.polynomial = model.albedo.at<float>(y, x);
      }
      shade(x, y, parts, n_dot_l);
    }
  }
}

}  // namespace

cv::Mat relight(const RelightModel& model, const Vec3& light, const Vec3& view) {
  cv::Mat out(model.normals.size(), CV_32FC1, cv::Scalar::all(0));
  for_each_lit_pixel(model, light, view, [&](int x, int y, const RelightingBrdfParts& parts, double n_dot_l) {
    out.at<float>(y, x) = static_cast<float>(std::max(parts.polynomial + parts.lobe, 0.0) * n_dot_l);
  });
  return out;
}

cv::Mat relight_colour(const RelightModel& model, const Vec3& light, const Vec3& view) {
  cv::Mat out(model.normals.size(), CV_32FC3, cv::Scalar::all(0));
  for_each_lit_pixel(model, light, view, [&](int x, int y, const RelightingBrdfParts& parts, double n_dot_l) {
    const cv::Vec3f chroma = model.chroma.empty() ? cv::Vec3f(1, 1, 1) : model.chroma.at<cv::Vec3f>(y, x);
    cv::Vec3f& o = out.at<cv::Vec3f>(y, x);
    for (int c = 0; c < 3; ++c)
      o[c] = static_cast<float>(std::max(chroma[c] * parts.polynomial + parts.lobe, 0.0) * n_dot_l);
  });
  return out;
}

std::vector<Vec3> turntable_lights(int count, double elevation_deg) {
  if (count < 1) fail("--turntable: needs at least 1 frame, got {}", count);
  if (!(elevation_deg > 0 && elevation_deg <= 90))
    fail("--elevation: must be in (0, 90] degrees, got {}", elevation_deg);
  std::vector<Vec3> lights;
  for (int i = 0; i < count; ++i)
    lights.push_back(direction_from_elevation_azimuth(rad_from_deg(elevation_deg), 2 * kPi * i / count));
  return lights;
}

}  // namespace lightstage
