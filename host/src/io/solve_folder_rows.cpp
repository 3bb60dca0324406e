#include "lightstage/host/io/solve_folder_rows.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/parallel.hpp"
#include "lightstage/host/io/exr.hpp"
#include "lightstage/host/io/normal_map.hpp"
#include "lightstage/host/io/row_reader.hpp"
#include "lightstage/host/reflectance/bipolynomial_model.hpp"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <vector>

namespace lightstage::io {

namespace fs = std::filesystem;

namespace {

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

double positive_number(const nlohmann::json& summary, const char* key, double otherwise) {
  const auto it = summary.find(key);
  if (it != summary.end() && it->is_number() && std::isfinite(it->get<double>()) && it->get<double>() > 0)
    return it->get<double>();
  return otherwise;
}

// A float map of one channel and the normal map's size, or an error naming the file.
std::unique_ptr<RowReader> open_float_plane(const fs::path& path, const cv::Size& size) {
  auto reader = open_row_reader(path);
  if (reader->type() != CV_32FC1 || reader->size() != size)
    fail("{}: expected one float channel of {}x{} (normal.png's size), got {} channel(s) of {}x{}",
         path.string(), size.width, size.height, CV_MAT_CN(reader->type()), reader->size().width,
         reader->size().height);
  return reader;
}

// The files.brdf names of a bi-polynomial fit, its order and lobe width recorded in `folder`.
std::vector<std::string> reflectance_files(SolveFolder& folder) {
  const auto& summary = folder.summary;
  const auto reflectance = summary.find("reflectance");
  if (reflectance == summary.end() || !reflectance->is_object()) return {};
  folder.reflectance = *reflectance;
  const auto files = summary.find("files");
  if (reflectance->value("model", "") != "bipolynomial" || files == summary.end() || !files->is_object() ||
      !files->contains("brdf"))
    return {};
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
  std::vector<std::string> out;
  for (const auto& name : names) {
    if (!name.is_string()) fail("{}: files.brdf must list file names", summary_path.string());
    out.push_back(name.get<std::string>());
  }
  folder.reflectance_order = order;
  folder.lobe_width = lobe_width;
  return out;
}

}  // namespace

SolveFolderRows::SolveFolderRows(const fs::path& dir) {
  if (!fs::is_directory(dir)) fail("{}: not a folder (expected a `solve` output folder)", dir.string());
  facts_.dir = dir;
  normal_png_ = open_row_reader(dir / "normal.png");  // its type is checked as its rows are decoded
  size_ = normal_png_->size();
  if (fs::exists(dir / "normal.exr")) {
    // The float normals, where normal.png holds one (the PNG is 16-bit).
    normal_exr_ = open_exr_rows(dir / "normal.exr", {"R", "G", "B"});
    if (normal_exr_->size() != size_)
      fail("{}: {}x{} but normal.png is {}x{}", (dir / "normal.exr").string(), normal_exr_->size().width,
           normal_exr_->size().height, size_.width, size_.height);
  }
  if (fs::exists(dir / "summary.json")) facts_.summary = read_summary(dir / "summary.json");
  facts_.albedo_png_scale = positive_number(facts_.summary, "albedo_png_scale", 1.0);
  if (fs::exists(dir / "albedo.pfm")) {
    albedo_pfm_ = open_float_plane(dir / "albedo.pfm", size_);
  } else if (fs::exists(dir / "albedo.png")) {
    albedo_png_ = open_row_reader(dir / "albedo.png");
    if (CV_MAT_CN(albedo_png_->type()) != 1 || albedo_png_->size() != size_)
      fail("{}: expected a grey image of {}x{} (normal.png's size)", (dir / "albedo.png").string(),
           size_.width, size_.height);
    facts_.albedo_from_png = true;
  }
  // Only what summary.json lists: an older colour solve's files may remain in a reused folder.
  const auto files = facts_.summary.find("files");
  if (has_albedo() && files != facts_.summary.end() && files->is_object() &&
      files->contains("albedo_colour_float")) {
    const auto& name = (*files)["albedo_colour_float"];
    if (!name.is_string())
      fail("{}: files.albedo_colour_float must be a file name", (dir / "summary.json").string());
    colour_ = open_row_reader(dir / name.get<std::string>());
    if (colour_->type() != CV_32FC3 || colour_->size() != size_)
      fail("{}: expected a colour PFM of {}x{} (normal.png's size)", colour_->path().string(), size_.width,
           size_.height);
    facts_.albedo_rgb_png_scale =
        positive_number(facts_.summary, "albedo_rgb_png_scale", facts_.albedo_png_scale);
  }
  if (fs::exists(dir / "residual.pfm")) residual_ = open_float_plane(dir / "residual.pfm", size_);
  if (fs::exists(dir / "confidence.pfm")) confidence_ = open_float_plane(dir / "confidence.pfm", size_);
  for (const auto& name : reflectance_files(facts_))
    coefficients_.push_back(open_float_plane(dir / name, size_));
}

SolveFolderRows::~SolveFolderRows() = default;

std::size_t SolveFolderRows::bytes_per_pixel() const {
  std::size_t bytes = 2 * 3 + 12 + 1;  // normal.png decoded to normals and their validity
  if (normal_exr_) bytes += 12;
  if (has_albedo()) bytes += 4 + 2;
  if (colour_) bytes += 2 * 12;  // the colour albedo and the chroma made from it
  if (residual_) bytes += 4;
  if (confidence_) bytes += 4;
  bytes += 2 * 4 * coefficients_.size();  // the planes and their merge
  return bytes;
}

SolveFolder SolveFolderRows::read(int y0, int rows, const Wanted& wanted, const cv::Mat& solved) {
  if (!solved.empty() && (solved.type() != CV_8UC1 || solved.rows != rows || solved.cols != size_.width))
    throw std::logic_error(
        fmt::format("SolveFolderRows::read: the solved mask is not {} rows of {}", rows, size_.width));
  SolveFolder band = facts_;
  const bool exact_normals = wanted.normals && normal_exr_;
  const bool decode_png = solved.empty() || (wanted.normals && !normal_exr_);
  // Each file decodes beside the others (normal.png and normal.exr are most of the work).
  DecodedNormals normals;
  cv::Mat exact;
  std::vector<std::function<void()>> files;
  if (decode_png)
    files.emplace_back([&] {
      cv::Mat encoded;
      normal_png_->read(y0, rows, encoded);
      normals = decode_normal_map(encoded, normal_png_->path().string());
    });
  if (exact_normals) files.emplace_back([&] { normal_exr_->read(y0, rows, exact); });
  files.emplace_back([&] { read_maps(y0, rows, wanted, band); });
  parallel_invoke(files, 0);
  band.solved = decode_png ? normals.valid : solved;
  if (exact_normals) {
    band.normals = cv::Mat(band.solved.size(), CV_32FC3, cv::Scalar::all(0));
    exact.copyTo(band.normals, band.solved);
  } else if (wanted.normals) {
    band.normals = normals.normals;
  }
  return band;
}

void SolveFolderRows::read_maps(int y0, int rows, const Wanted& wanted, SolveFolder& band) {
  const bool colour = wanted.colour && colour_;
  if (wanted.albedo || colour) {
    if (albedo_pfm_) {
      albedo_pfm_->read(y0, rows, band.albedo);
    } else if (albedo_png_) {
      cv::Mat png;
      albedo_png_->read(y0, rows, png);
      png.convertTo(band.albedo, CV_32FC1,
                    facts_.albedo_png_scale / (png.depth() == CV_16U ? 65535.0 : 255.0));
    }
  }
  if (colour) {
    // The colour albedo over the grey albedo: the chroma (neutral where the albedo is 0).
    cv::Mat colour_albedo;
    colour_->read(y0, rows, colour_albedo);
    band.chroma = cv::Mat(colour_albedo.size(), CV_32FC3, cv::Scalar::all(1));
    for (int y = 0; y < colour_albedo.rows; ++y) {
      for (int x = 0; x < colour_albedo.cols; ++x) {
        const float a = band.albedo.at<float>(y, x);
        if (a > 0) band.chroma.at<cv::Vec3f>(y, x) = colour_albedo.at<cv::Vec3f>(y, x) / a;
      }
    }
  }
  if (wanted.residual && residual_) residual_->read(y0, rows, band.residual);
  if (wanted.confidence && confidence_) confidence_->read(y0, rows, band.confidence);
  if (wanted.coefficients && !coefficients_.empty()) {
    std::vector<cv::Mat> planes(coefficients_.size());
    for (std::size_t i = 0; i < planes.size(); ++i) coefficients_[i]->read(y0, rows, planes[i]);
    cv::merge(planes, band.coefficients);
  }
}

}  // namespace lightstage::io
