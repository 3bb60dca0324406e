#include "lightstage/host/io/solve_output.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/version.hpp"
#include "lightstage/host/io/exr.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/normal_map.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/reflectance/bipolynomial_model.hpp"
#include "util/atomic_file.hpp"
#include "util/utc_time.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <system_error>
#include <vector>

namespace lightstage::io {

namespace {

// A PNG's white: the 99.5th percentile of every channel of `values` (CV_32FC1
// or CV_32FC3) over the solved pixels, so that saturated colours keep their
// hue; 1 when there are none or it is not positive.
double png_white(const cv::Mat& values, const cv::Mat& solved) {
  const int channels = values.channels();
  std::vector<float> all;
  for (int y = 0; y < values.rows; ++y) {
    const float* row = values.ptr<float>(y);
    for (int x = 0; x < values.cols; ++x)
      if (solved.at<std::uint8_t>(y, x) != 0)
        all.insert(all.end(), row + x * channels, row + (x + 1) * channels);
  }
  if (all.empty()) return 1.0;
  const auto index = static_cast<std::size_t>(std::floor(0.995 * static_cast<double>(all.size() - 1)));
  std::nth_element(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(index), all.end());
  const double scale = all[index];
  return std::isfinite(scale) && scale > 0 ? scale : 1.0;
}

// albedo (CV_32FC1) · chroma (CV_32FC3, BGR) per channel.
cv::Mat times_chroma(const cv::Mat& albedo, const cv::Mat& chroma) {
  cv::Mat albedo3;
  cv::merge(std::vector<cv::Mat>{albedo, albedo, albedo}, albedo3);
  return albedo3.mul(chroma);
}

}  // namespace

double albedo_png_scale(const SolveResult& result) { return png_white(result.albedo, result.solved); }

namespace {

// method_map.png's colours (RGB), one per choice in order; unsolved pixels are black.
constexpr std::array<std::array<std::uint8_t, 3>, 8> kChoiceColours = {{{31, 119, 180},
                                                                        {255, 127, 14},
                                                                        {44, 160, 44},
                                                                        {214, 39, 40},
                                                                        {148, 103, 189},
                                                                        {140, 86, 75},
                                                                        {227, 119, 194},
                                                                        {188, 189, 34}}};

// The choice map as a picture, and its legend and counts under summary.method_map.
void write_method_map(const std::filesystem::path& path, const SolveResult& result, nlohmann::json& summary) {
  if (result.choice.type() != CV_8UC1 || result.choice.size() != result.normals.size())
    fail("{}: the choice map must be CV_8UC1 of the normals' size", path.string());
  if (result.choices.size() > kChoiceColours.size())
    fail("{}: {} choices, at most {} have colours", path.string(), result.choices.size(),
         kChoiceColours.size());
  cv::Mat picture(result.choice.size(), CV_8UC3, cv::Scalar::all(0));
  std::vector<std::size_t> counts(result.choices.size(), 0);
  for (int y = 0; y < picture.rows; ++y) {
    for (int x = 0; x < picture.cols; ++x) {
      const int k = result.choice.at<std::uint8_t>(y, x);
      if (k == 0 || k > static_cast<int>(counts.size())) continue;
      ++counts[static_cast<std::size_t>(k - 1)];
      const auto& rgb = kChoiceColours[static_cast<std::size_t>(k - 1)];
      picture.at<cv::Vec3b>(y, x) = cv::Vec3b(rgb[2], rgb[1], rgb[0]);  // OpenCV stores BGR
    }
  }
  write_png(path, picture);
  nlohmann::json legend = nlohmann::json::array();
  for (std::size_t k = 0; k < counts.size(); ++k) {
    const auto& rgb = kChoiceColours[k];
    legend.push_back({{"method", result.choices[k]},
                      {"pixels", counts[k]},
                      {"colour", fmt::format("#{:02x}{:02x}{:02x}", rgb[0], rgb[1], rgb[2])}});
  }
  summary["method_map"] = {{"file", path.filename().string()}, {"choices", legend}};
  summary["files"]["method_map"] = path.filename().string();
}

// albedo · chroma (CV_32FC3, BGR) for a colour result, else empty.
cv::Mat colour_albedo(const std::filesystem::path& dir, const SolveResult& result) {
  if (result.chroma.empty()) return {};
  if (result.chroma.type() != CV_32FC3 || result.chroma.size() != result.albedo.size())
    fail("{}: cannot write solver outputs: the chroma must be CV_32FC3 of the albedo's size", dir.string());
  return times_chroma(result.albedo, result.chroma);
}

}  // namespace

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
  write_exr(dir / "normal.exr", result.normals, {"R", "G", "B"});  // R = x, as in normal.png
  write_exr(dir / "albedo.exr", result.albedo, {"Y"});
  const cv::Mat colour = colour_albedo(dir, result);
  const double colour_scale = colour.empty() ? scale : png_white(colour, result.solved);
  if (!colour.empty()) {
    write_pfm(dir / "albedo_rgb.pfm", colour);
    write_exr(dir / "albedo_rgb.exr", colour, {"B", "G", "R"});
    cv::Mat colour16;
    cv::Mat shown = colour / colour_scale;
    cv::min(shown, 1.0, shown);
    cv::max(shown, 0.0, shown);
    shown.convertTo(colour16, CV_16UC3, 65535.0);
    write_png16(dir / "albedo_rgb.png", colour16);
  }

  nlohmann::json summary = result.summary.to_json();
  summary["parameters"] = result.parameters;
  summary["time"] = util::utc_timestamp();
  summary["input"] = input.string();
  summary["software"] = std::string("lightstage ") + kVersion;
  summary["width"] = result.normals.cols;
  summary["height"] = result.normals.rows;
  summary["albedo_png_scale"] = scale;
  summary["files"] = {{"normals", "normal.png"},    {"normals_visualisation", "normal_vis.png"},
                      {"albedo", "albedo.png"},     {"albedo_float", "albedo.pfm"},
                      {"residual", "residual.pfm"}, {"normals_exr", "normal.exr"},
                      {"albedo_exr", "albedo.exr"}};
  if (!colour.empty()) {
    summary["albedo_rgb_png_scale"] = colour_scale;
    summary["files"]["albedo_colour"] = "albedo_rgb.png";
    summary["files"]["albedo_colour_float"] = "albedo_rgb.pfm";
    summary["files"]["albedo_colour_exr"] = "albedo_rgb.exr";
  }
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
  if (!result.choice.empty()) write_method_map(dir / "method_map.png", result, summary);
  if (!result.reflectance.is_null()) summary["reflectance"] = result.reflectance;
  for (const auto& [key, value] : extra.items()) summary[key] = value;
  util::write_text_atomic(dir / "summary.json", summary.dump(2) + "\n");
  return summary;
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
