#include "lightstage/host/io/solve_output.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/version.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/normal_map.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "util/atomic_file.hpp"
#include "util/utc_time.hpp"

#include <algorithm>
#include <cmath>
#include <system_error>
#include <vector>

namespace lightstage::io {

double albedo_png_scale(const SolveResult& result) {
  std::vector<float> values;
  for (int y = 0; y < result.albedo.rows; ++y) {
    for (int x = 0; x < result.albedo.cols; ++x) {
      if (result.solved.at<std::uint8_t>(y, x) != 0) values.push_back(result.albedo.at<float>(y, x));
    }
  }
  if (values.empty()) return 1.0;
  const auto index = static_cast<std::size_t>(std::floor(0.995 * static_cast<double>(values.size() - 1)));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(index), values.end());
  const double scale = values[index];
  return std::isfinite(scale) && scale > 0 ? scale : 1.0;
}

nlohmann::json write_solve_outputs(const std::filesystem::path& dir, const SolveResult& result,
                                   const std::filesystem::path& input, const nlohmann::json& extra) {
  if (result.normals.type() != CV_32FC3 || result.albedo.type() != CV_32FC1 ||
      result.residual.type() != CV_32FC1 || result.solved.type() != CV_8UC1 ||
      result.albedo.size() != result.normals.size() || result.residual.size() != result.normals.size() ||
      result.solved.size() != result.normals.size()) {
    fail("{}: cannot write solver outputs: result maps are missing or of the wrong type/size", dir.string());
  }
  if (!extra.is_object())
    fail("{}: summary extras must be a JSON object, got {}", dir.string(), extra.type_name());
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error) fail("{}: cannot create folder: {}", dir.string(), error.message());

  write_normal_map(dir / "normal.png", result.normals, result.solved);
  write_normal_visualisation(dir / "normal_vis.png", result.normals, result.solved);
  const double scale = albedo_png_scale(result);
  cv::Mat albedo16;
  cv::Mat scaled = result.albedo / scale;
  cv::min(scaled, 1.0, scaled);
  cv::max(scaled, 0.0, scaled);
  scaled.convertTo(albedo16, CV_16UC1, 65535.0);  // convertTo rounds to nearest
  write_png16(dir / "albedo.png", albedo16);
  write_pfm(dir / "albedo.pfm", result.albedo);
  write_pfm(dir / "residual.pfm", result.residual);

  nlohmann::json summary = result.summary.to_json();
  summary["parameters"] = result.parameters;
  summary["time"] = util::utc_timestamp();
  summary["input"] = input.string();
  summary["software"] = std::string("lightstage ") + kVersion;
  summary["width"] = result.normals.cols;
  summary["height"] = result.normals.rows;
  summary["albedo_png_scale"] = scale;
  summary["files"] = {{"normals", "normal.png"},
                      {"normals_visualisation", "normal_vis.png"},
                      {"albedo", "albedo.png"},
                      {"albedo_float", "albedo.pfm"},
                      {"residual", "residual.pfm"}};
  // Optional per-pixel outputs: confidence and a per-pixel reflectance model (one PFM per coefficient).
  if (!result.confidence.empty()) {
    write_pfm(dir / "confidence.pfm", result.confidence);
    summary["files"]["confidence"] = "confidence.pfm";
  }
  if (!result.coefficients.empty()) {
    std::vector<cv::Mat> planes;
    cv::split(result.coefficients, planes);
    nlohmann::json names = nlohmann::json::array();
    const auto& terms = result.reflectance.is_object()
                            ? result.reflectance.value("terms", nlohmann::json::array())
                            : nlohmann::json::array();
    for (std::size_t c = 0; c < planes.size(); ++c) {
      const std::string term = c < terms.size() ? terms[c].get<std::string>() : std::to_string(c);
      const std::string name = "brdf_" + term + ".pfm";
      write_pfm(dir / name, planes[c]);
      names.push_back(name);
    }
    summary["files"]["brdf"] = names;
  }
  if (!result.reflectance.is_null()) summary["reflectance"] = result.reflectance;
  for (const auto& [key, value] : extra.items()) summary[key] = value;
  util::write_text_atomic(dir / "summary.json", summary.dump(2) + "\n");
  return summary;
}

}  // namespace lightstage::io
