#include "lightstage/host/io/solve_output.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/io/exr.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/normal_map.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/reflectance/bipolynomial_model.hpp"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <vector>

namespace lightstage::io {

cv::Mat times_chroma(const cv::Mat& albedo, const cv::Mat& chroma) {
  cv::Mat albedo3;
  cv::merge(std::vector<cv::Mat>{albedo, albedo, albedo}, albedo3);
  return albedo3.mul(chroma);
}

namespace {

namespace fs = std::filesystem;

// A float map of one channel and the normal map's size, or an error naming the file.
cv::Mat read_float_plane(const fs::path& path, const cv::Size& size) {
  cv::Mat plane = read_pfm(path);
  if (plane.type() != CV_32FC1 || plane.size() != size)
    fail("{}: expected one float channel of {}x{} (normal.png's size), got {} channel(s) of {}x{}",
         path.string(), size.width, size.height, plane.channels(), plane.cols, plane.rows);
  return plane;
}

nlohmann::json read_summary(const fs::path& path) {
  std::ifstream in(path);
  if (!in) fail("{}: cannot open", path.string());
  nlohmann::json summary;
  try {
    in >> summary;
  } catch (const std::exception& e) {
    fail("{}: not valid JSON: {}", path.string(), e.what());
  }
  if (!summary.is_object()) fail("{}: expected a JSON object", path.string());
  return summary;
}

// files.brdf of a bi-polynomial fit, merged into one CV_32FC(k) map.
void read_reflectance(SolveFolder& folder) {
  const auto& summary = folder.summary;
  const auto reflectance = summary.find("reflectance");
  if (reflectance == summary.end() || !reflectance->is_object()) return;
  folder.reflectance = *reflectance;
  const auto files = summary.find("files");
  if (reflectance->value("model", "") != "bipolynomial" || files == summary.end() || !files->is_object() ||
      !files->contains("brdf"))
    return;
  const fs::path summary_path = folder.dir / "summary.json";
  const int order = reflectance->value("order", 0);
  if (order < 1 || order > 3)
    fail("{}: reflectance.order must be 1, 2 or 3 for a bi-polynomial, got {}", summary_path.string(), order);
  double lobe_width = 0;
  if (const auto specular = reflectance->find("specular");
      specular != reflectance->end() && !specular->is_null()) {
    const auto width = specular->is_object() ? specular->find("width") : specular->end();
    if (width == specular->end() || !width->is_number() ||
        !(width->get<double>() > 0 && width->get<double>() <= kMaxLobeWidth))
      fail("{}: reflectance.specular.width must be a number in (0, {}]", summary_path.string(),
           kMaxLobeWidth);
    lobe_width = width->get<double>();
  }
  const auto& names = (*files)["brdf"];
  const int terms = bipolynomial_term_count(order) + (lobe_width > 0 ? 1 : 0);
  if (!names.is_array() || static_cast<int>(names.size()) != terms)
    fail("{}: files.brdf must list {} coefficient maps for order {}{}", summary_path.string(), terms, order,
         lobe_width > 0 ? " and a specular lobe" : "");
  std::vector<cv::Mat> planes;
  for (const auto& name : names) {
    if (!name.is_string()) fail("{}: files.brdf must list file names", summary_path.string());
    planes.push_back(read_float_plane(folder.dir / name.get<std::string>(), folder.normals.size()));
  }
  cv::merge(planes, folder.coefficients);
  folder.reflectance_order = order;
  folder.lobe_width = lobe_width;
}

// albedo_rgb.pfm over the grey albedo: the chroma (neutral where the albedo is 0).
cv::Mat read_chroma(const fs::path& dir, const SolveFolder& folder) {
  const auto& name = folder.summary["files"]["albedo_colour_float"];
  if (!name.is_string())
    fail("{}: files.albedo_colour_float must be a file name", (dir / "summary.json").string());
  const fs::path path = dir / name.get<std::string>();
  const cv::Mat colour = read_pfm(path);
  if (colour.type() != CV_32FC3 || colour.size() != folder.albedo.size())
    fail("{}: expected a colour PFM of {}x{} (normal.png's size)", path.string(), folder.albedo.cols,
         folder.albedo.rows);
  cv::Mat chroma(colour.size(), CV_32FC3, cv::Scalar::all(1));
  for (int y = 0; y < colour.rows; ++y) {
    for (int x = 0; x < colour.cols; ++x) {
      const float a = folder.albedo.at<float>(y, x);
      if (a > 0) chroma.at<cv::Vec3f>(y, x) = colour.at<cv::Vec3f>(y, x) / a;
    }
  }
  return chroma;
}

}  // namespace

cv::Mat SolveFolder::colour_albedo() const {
  return albedo.empty() || chroma.empty() ? albedo : times_chroma(albedo, chroma);
}

cv::Mat SolveFolder::display_albedo() const {
  if (albedo.empty()) return {};
  cv::Mat shown = colour_albedo() / (chroma.empty() ? albedo_png_scale : albedo_rgb_png_scale);
  cv::min(shown, 1.0, shown);
  cv::max(shown, 0.0, shown);
  return shown;
}

SolveFolder read_solve_folder(const fs::path& dir) {
  if (!fs::is_directory(dir)) fail("{}: not a folder (expected a `solve` output folder)", dir.string());
  SolveFolder folder;
  folder.dir = dir;
  const DecodedNormals normals = read_normal_map(dir / "normal.png");
  folder.normals = normals.normals;
  folder.solved = normals.valid;
  const cv::Size size = folder.normals.size();
  if (fs::exists(dir / "normal.exr")) {
    // The float normals, where normal.png holds one (the PNG is 16-bit).
    const cv::Mat exact = read_exr(dir / "normal.exr", {"R", "G", "B"});
    if (exact.size() != size)
      fail("{}: {}x{} but normal.png is {}x{}", (dir / "normal.exr").string(), exact.cols, exact.rows,
           size.width, size.height);
    folder.normals = cv::Mat(size, CV_32FC3, cv::Scalar::all(0));
    exact.copyTo(folder.normals, folder.solved);
  }
  if (fs::exists(dir / "summary.json")) folder.summary = read_summary(dir / "summary.json");
  const auto scale = folder.summary.find("albedo_png_scale");
  if (scale != folder.summary.end() && scale->is_number() && std::isfinite(scale->get<double>()) &&
      scale->get<double>() > 0)
    folder.albedo_png_scale = scale->get<double>();
  if (fs::exists(dir / "albedo.pfm")) {
    folder.albedo = read_float_plane(dir / "albedo.pfm", size);
  } else if (fs::exists(dir / "albedo.png")) {
    const cv::Mat png = read_image(dir / "albedo.png");
    if (png.channels() != 1 || png.size() != size)
      fail("{}: expected a grey image of {}x{} (normal.png's size)", (dir / "albedo.png").string(),
           size.width, size.height);
    png.convertTo(folder.albedo, CV_32FC1,
                  folder.albedo_png_scale / (png.depth() == CV_16U ? 65535.0 : 255.0));
    folder.albedo_from_png = true;
  }
  // Only what summary.json lists: an older colour solve's files may remain in a reused folder.
  const auto files = folder.summary.find("files");
  if (!folder.albedo.empty() && files != folder.summary.end() && files->is_object() &&
      files->contains("albedo_colour_float")) {
    folder.chroma = read_chroma(dir, folder);
    const auto colour_scale = folder.summary.find("albedo_rgb_png_scale");
    folder.albedo_rgb_png_scale = folder.albedo_png_scale;
    if (colour_scale != folder.summary.end() && colour_scale->is_number() &&
        std::isfinite(colour_scale->get<double>()) && colour_scale->get<double>() > 0)
      folder.albedo_rgb_png_scale = colour_scale->get<double>();
  }
  if (fs::exists(dir / "residual.pfm")) folder.residual = read_float_plane(dir / "residual.pfm", size);
  if (fs::exists(dir / "confidence.pfm")) folder.confidence = read_float_plane(dir / "confidence.pfm", size);
  read_reflectance(folder);
  return folder;
}

}  // namespace lightstage::io
