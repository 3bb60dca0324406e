#include "lightstage/host/reflectance/relight.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/io/normal_map.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/reflectance/bipolynomial_model.hpp"

#include <fstream>
#include <vector>

namespace lightstage {

RelightModel load_relight_model(const std::filesystem::path& dir) {
  if (!std::filesystem::is_directory(dir))
    fail("--input {}: not a folder (expected a `solve` output folder)", dir.string());
  RelightModel model;
  const auto normals = io::read_normal_map(dir / "normal.png");
  model.normals = normals.normals;
  model.solved = normals.valid;
  const auto albedo_path = dir / "albedo.pfm";
  if (std::filesystem::exists(albedo_path)) {
    model.albedo = io::read_pfm(albedo_path);
    if (model.albedo.size() != model.normals.size() || model.albedo.channels() != 1)
      fail("{}: albedo does not match normal.png ({}x{})", albedo_path.string(), model.normals.cols,
           model.normals.rows);
  } else {
    model.albedo = cv::Mat(model.normals.size(), CV_32FC1, cv::Scalar::all(1));
  }
  const auto summary_path = dir / "summary.json";
  if (!std::filesystem::exists(summary_path)) return model;
  nlohmann::json summary;
  try {
    std::ifstream(summary_path) >> summary;
  } catch (const std::exception& e) {
    fail("{}: not valid JSON: {}", summary_path.string(), e.what());
  }
  if (!summary.contains("reflectance") || !summary["reflectance"].is_object()) return model;
  const auto& reflectance = summary["reflectance"];
  if (reflectance.value("model", "") != "bipolynomial" || !summary.contains("files") ||
      !summary["files"].contains("brdf"))
    return model;
  const int order = reflectance.value("order", 0);
  const int terms = bipolynomial_term_count(order);
  const auto& files = summary["files"]["brdf"];
  if (!files.is_array() || static_cast<int>(files.size()) != terms)
    fail("{}: files.brdf must list {} coefficient maps for order {}", summary_path.string(), terms, order);
  std::vector<cv::Mat> planes;
  for (const auto& name : files) {
    const auto path = dir / name.get<std::string>();
    cv::Mat plane = io::read_pfm(path);
    if (plane.size() != model.normals.size() || plane.type() != CV_32FC1)
      fail("{}: coefficient map does not match normal.png ({}x{})", path.string(), model.normals.cols,
           model.normals.rows);
    planes.push_back(plane);
  }
  cv::merge(planes, model.coefficients);
  model.order = order;
  return model;
}

cv::Mat relight(const RelightModel& model, const Vec3& light_in, const Vec3& view) {
  if (!(light_in.norm() > 0)) fail("--light: a light direction must not be zero");
  const Vec3 l = light_in.normalized();
  const Vec3 h = (l + view).normalized();
  cv::Mat out(model.normals.size(), CV_32FC1, cv::Scalar::all(0));
  const int k = model.order > 0 ? bipolynomial_term_count(model.order) : 0;
  Eigen::VectorXd c(std::max(k, 1));
  for (int y = 0; y < out.rows; ++y) {
    for (int x = 0; x < out.cols; ++x) {
      if (model.solved.at<std::uint8_t>(y, x) == 0) continue;
      const cv::Vec3f v = model.normals.at<cv::Vec3f>(y, x);
      const Vec3 n(v[0], v[1], v[2]);
      const double shade = n.dot(l);
      if (shade <= 0) continue;
      double rho;
      if (k > 0) {
        const float* row = model.coefficients.ptr<float>(y) + static_cast<std::ptrdiff_t>(x) * k;
        for (int t = 0; t < k; ++t) c(t) = row[t];
        rho = std::max(evaluate_bipolynomial(model.order, c, n.dot(h), l.dot(h)), 0.0);
      } else {
        rho = model.albedo.at<float>(y, x);
      }
      out.at<float>(y, x) = static_cast<float>(rho * shade);
    }
  }
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
