#include "lightstage/host/io/solve_output_writer.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/parallel.hpp"
#include "lightstage/common/version.hpp"
#include "lightstage/host/io/normal_map.hpp"
#include "lightstage/host/io/row_reader.hpp"
#include "lightstage/host/io/solve_output.hpp"
#include "util/atomic_file.hpp"
#include "util/utc_time.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <functional>
#include <system_error>
#include <utility>
#include <vector>

namespace lightstage::io {
namespace {

namespace fs = std::filesystem;

// The PNGs' white: this quantile of the solved values (every channel), so that saturated colours keep their
// hue.
constexpr double kPngWhite = 0.995;
// Rows read back at a time for the PNG scales.
constexpr int kReadBackRows = 256;

// method_map.png's colours (RGB), one per choice in order; unsolved pixels are black.
constexpr std::array<std::array<std::uint8_t, 3>, 8> kChoiceColours = {{{31, 119, 180},
                                                                        {255, 127, 14},
                                                                        {44, 160, 44},
                                                                        {214, 39, 40},
                                                                        {148, 103, 189},
                                                                        {140, 86, 75},
                                                                        {227, 119, 194},
                                                                        {188, 189, 34}}};

// Floats as unsigned keys in the same order (negative values reversed below the positive ones).
std::uint32_t order_key(float v) {
  const auto bits = std::bit_cast<std::uint32_t>(v);
  return (bits & 0x80000000U) != 0 ? ~bits : bits | 0x80000000U;
}

// `values` / white, clamped to [0, 1], as 16-bit (rounded to nearest).
cv::Mat png16(const cv::Mat& values, double white) {
  cv::Mat shown = values / white;
  cv::min(shown, 1.0, shown);
  cv::max(shown, 0.0, shown);
  cv::Mat out;
  shown.convertTo(out, CV_MAKETYPE(CV_16U, values.channels()), 65535.0);
  return out;
}

// Calls `visit(rows, y0)` for the rows of a float map already written, a few at a time.
template <typename Visit>
void read_back(const fs::path& file, Visit&& visit) {
  const auto reader = open_row_reader(file);
  cv::Mat rows;
  for (int y0 = 0; y0 < reader->size().height; y0 += kReadBackRows) {
    reader->read(y0, std::min(kReadBackRows, reader->size().height - y0), rows);
    visit(rows, y0);
  }
}

// Counts the solved pixels' values of `map` (every channel) toward its PNG's white.
void count_white(BandQuantile& white, const cv::Mat& map, const cv::Mat& solved) {
  const auto channels = static_cast<std::size_t>(map.channels());
  for (int y = 0; y < map.rows; ++y) {
    const auto* lit = solved.ptr<std::uint8_t>(y);
    const float* values = map.ptr<float>(y);
    for (int x = 0; x < map.cols; ++x)
      if (lit[x] != 0) white.count(values + channels * static_cast<std::size_t>(x), channels);
  }
}

void check_band(const SolveResult& band, cv::Size size, const fs::path& dir) {
  const cv::Size rows = band.normals.size();
  if (band.normals.type() != CV_32FC3 || band.albedo.type() != CV_32FC1 || band.residual.type() != CV_32FC1 ||
      band.solved.type() != CV_8UC1 || band.albedo.size() != rows || band.residual.size() != rows ||
      band.solved.size() != rows || rows.width != size.width)
    fail("{}: cannot write solver outputs: result maps are missing or of the wrong type/size", dir.string());
  if (!band.chroma.empty() && (band.chroma.type() != CV_32FC3 || band.chroma.size() != rows))
    fail("{}: cannot write solver outputs: the chroma must be CV_32FC3 of the albedo's size", dir.string());
  if (!band.choice.empty() && (band.choice.type() != CV_8UC1 || band.choice.size() != rows))
    fail("{}: the choice map must be CV_8UC1 of the normals' size", (dir / "method_map.png").string());
}

}  // namespace

void BandQuantile::count(const float* values, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(values[i])) continue;
    ++histogram_[order_key(values[i]) >> 16];
    ++total_;
  }
}

bool BandQuantile::locate(double q) {
  if (total_ == 0) return false;
  auto index = static_cast<std::uint64_t>(std::floor(q * static_cast<double>(total_ - 1)));
  for (std::uint32_t b = 0; b < histogram_.size(); ++b) {
    if (index < histogram_[b]) {
      bucket_ = b;
      rank_ = index;
      std::fill(histogram_.begin(), histogram_.end(), 0);  // now the bucket's low 16 bits
      return true;
    }
    index -= histogram_[b];
  }
  return false;  // unreachable: the index is below the total
}

void BandQuantile::gather(const float* values, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(values[i])) continue;
    const std::uint32_t key = order_key(values[i]);
    if (key >> 16 == bucket_) ++histogram_[key & 0xffffU];
  }
}

float BandQuantile::value() const {
  std::uint64_t index = rank_;
  for (std::uint32_t low = 0; low < histogram_.size(); ++low) {
    if (index < histogram_[low]) {
      // The key back to its float.
      const std::uint32_t key = bucket_ << 16 | low;
      return std::bit_cast<float>((key & 0x80000000U) != 0 ? key & 0x7fffffffU : ~key);
    }
    index -= histogram_[low];
  }
  fail("BandQuantile: the values gathered again are not the values counted");
}

SolveOutputWriter::SolveOutputWriter(fs::path dir, cv::Size size) : dir_(std::move(dir)), size_(size) {
  std::error_code error;
  created_ = !fs::exists(dir_, error);
  fs::create_directories(dir_, error);
  if (error) fail("{}: cannot create folder: {}", dir_.string(), error.message());
  solved_ = cv::Mat(size_, CV_8UC1, cv::Scalar(0));
}

SolveOutputWriter::~SolveOutputWriter() {
  if (finished_) return;
  // Unfinished: the temporary files go, and the folder when this writer made it.
  for (auto* writer : {&normal_png_, &normal_vis_, &albedo_pfm_, &residual_pfm_, &normal_exr_, &albedo_exr_,
                       &colour_pfm_, &colour_exr_, &confidence_pfm_, &method_map_})
    writer->reset();
  coefficient_pfms_.clear();
  std::error_code ignored;
  for (const fs::path& file : committed_) fs::remove(file, ignored);  // a finish that failed half way
  if (created_ && fs::is_empty(dir_, ignored)) fs::remove(dir_, ignored);
}

void SolveOutputWriter::open(const SolveResult& band) {
  colour_ = !band.chroma.empty();
  normal_png_ = open_png_writer(dir_ / "normal.png", size_, CV_16UC3);
  normal_vis_ = open_png_writer(dir_ / "normal_vis.png", size_, CV_8UC3);
  albedo_pfm_ = open_pfm_writer(dir_ / "albedo.pfm", size_, CV_32FC1);
  residual_pfm_ = open_pfm_writer(dir_ / "residual.pfm", size_, CV_32FC1);
  normal_exr_ =
      open_exr_writer(dir_ / "normal.exr", size_, CV_32FC3, {"R", "G", "B"});  // R = x, as normal.png
  albedo_exr_ = open_exr_writer(dir_ / "albedo.exr", size_, CV_32FC1, {"Y"});
  if (colour_) {
    colour_pfm_ = open_pfm_writer(dir_ / "albedo_rgb.pfm", size_, CV_32FC3);
    colour_exr_ = open_exr_writer(dir_ / "albedo_rgb.exr", size_, CV_32FC3, {"B", "G", "R"});
  }
  if (!band.confidence.empty()) confidence_pfm_ = open_pfm_writer(dir_ / "confidence.pfm", size_, CV_32FC1);
  if (!band.coefficients.empty()) {
    const nlohmann::json terms = band.reflectance.is_object()
                                     ? band.reflectance.value("terms", nlohmann::json::array())
                                     : nlohmann::json::array();
    for (int c = 0; c < band.coefficients.channels(); ++c) {
      const auto k = static_cast<std::size_t>(c);
      const std::string term =
          k < terms.size() && terms[k].is_string() ? terms[k].get<std::string>() : std::to_string(c);
      coefficient_files_.push_back("brdf_" + term + ".pfm");
      coefficient_pfms_.push_back(open_pfm_writer(dir_ / coefficient_files_.back(), size_, CV_32FC1));
    }
  }
  if (!band.choice.empty()) {
    if (band.choices.size() > kChoiceColours.size())
      fail("{}: {} choices, at most {} have colours", (dir_ / "method_map.png").string(), band.choices.size(),
           kChoiceColours.size());
    choices_ = band.choices;
    choice_counts_.assign(choices_.size(), 0);
    method_map_ = open_png_writer(dir_ / "method_map.png", size_, CV_8UC3);
  }
  opened_ = true;
  const int empty = std::exchange(pending_empty_, 0);
  rows_ -= empty;
  add_empty(empty);
}

void SolveOutputWriter::add_empty(int rows) {
  if (rows <= 0) return;
  if (rows > size_.height - rows_)
    fail("{}: {} more rows given after {} of {}", dir_.string(), rows, rows_, size_.height);
  if (!opened_) {
    pending_empty_ += rows;
    rows_ += rows;
    return;
  }
  SolveResult zeros;
  const cv::Size band(size_.width, rows);
  zeros.normals = cv::Mat(band, CV_32FC3, cv::Scalar::all(0));
  zeros.albedo = cv::Mat(band, CV_32FC1, cv::Scalar::all(0));
  zeros.residual = cv::Mat(band, CV_32FC1, cv::Scalar::all(0));
  zeros.solved = cv::Mat(band, CV_8UC1, cv::Scalar::all(0));
  if (colour_) zeros.chroma = cv::Mat(band, CV_32FC3, cv::Scalar::all(0));
  if (confidence_pfm_) zeros.confidence = cv::Mat(band, CV_32FC1, cv::Scalar::all(0));
  if (!coefficient_pfms_.empty())
    zeros.coefficients =
        cv::Mat(band, CV_32FC(static_cast<int>(coefficient_pfms_.size())), cv::Scalar::all(0));
  if (method_map_) zeros.choice = cv::Mat(band, CV_8UC1, cv::Scalar::all(0));
  write_rows(zeros);
}

void SolveOutputWriter::add(const SolveResult& band) {
  check_band(band, size_, dir_);
  if (band.normals.rows > size_.height - rows_)
    fail("{}: {} more rows given after {} of {}", dir_.string(), band.normals.rows, rows_, size_.height);
  if (!opened_) open(band);
  write_rows(band);
}

void SolveOutputWriter::write_rows(const SolveResult& band) {
  const int rows = band.normals.rows;
  const auto need = [&](const cv::Mat& map, bool wanted, const char* what) {
    if (map.empty() == wanted)
      fail("{}: rows {}-{}: {} {} where the rows above {}", dir_.string(), rows_, rows_ + rows - 1,
           wanted ? "no" : "a", what, wanted ? "had one" : "had none");
  };
  need(band.chroma, colour_, "colour");
  need(band.confidence, confidence_pfm_ != nullptr, "confidence map");
  need(band.coefficients, !coefficient_pfms_.empty(), "reflectance model");
  need(band.choice, method_map_ != nullptr, "method map");
  if (!band.confidence.empty() &&
      (band.confidence.type() != CV_32FC1 || band.confidence.size() != band.normals.size()))
    fail("{}: rows {}-{}: the confidence must be CV_32FC1 of the normals' size", dir_.string(), rows_,
         rows_ + rows - 1);
  if (!coefficient_pfms_.empty() &&
      (band.coefficients.channels() != static_cast<int>(coefficient_pfms_.size()) ||
       band.coefficients.size() != band.normals.size() || band.coefficients.depth() != CV_32F))
    fail("{}: rows {}-{}: the reflectance model has {} coefficients, the rows above {}", dir_.string(), rows_,
         rows_ + rows - 1, band.coefficients.channels(), coefficient_pfms_.size());
  band.solved.copyTo(solved_.rowRange(rows_, rows_ + rows));
  // The files encode side by side (the float maps together; each file's rows still in order).
  std::vector<std::function<void()>> files;
  files.emplace_back([&] { normal_png_->write(encode_normal_map(band.normals, band.solved)); });
  files.emplace_back([&] { normal_vis_->write(normal_visualisation(band.normals, band.solved)); });
  files.emplace_back([&] { normal_exr_->write(band.normals); });
  files.emplace_back([&] {
    albedo_pfm_->write(band.albedo);
    residual_pfm_->write(band.residual);
    albedo_exr_->write(band.albedo);
    count_white(albedo_white_, band.albedo, band.solved);
    if (confidence_pfm_) confidence_pfm_->write(band.confidence);
  });
  if (colour_)
    files.emplace_back([&] {
      const cv::Mat colour = times_chroma(band.albedo, band.chroma);
      colour_pfm_->write(colour);
      colour_exr_->write(colour);
      count_white(colour_white_, colour, band.solved);
    });
  if (!coefficient_pfms_.empty())
    files.emplace_back([&] {
      std::vector<cv::Mat> planes;
      cv::split(band.coefficients, planes);
      for (std::size_t c = 0; c < planes.size(); ++c) coefficient_pfms_[c]->write(planes[c]);
    });
  if (method_map_)
    files.emplace_back([&] {
      cv::Mat picture(band.choice.size(), CV_8UC3, cv::Scalar::all(0));
      for (int y = 0; y < picture.rows; ++y) {
        for (int x = 0; x < picture.cols; ++x) {
          const int k = band.choice.at<std::uint8_t>(y, x);
          if (k == 0 || k > static_cast<int>(choice_counts_.size())) continue;
          ++choice_counts_[static_cast<std::size_t>(k - 1)];
          const auto& rgb = kChoiceColours[static_cast<std::size_t>(k - 1)];
          picture.at<cv::Vec3b>(y, x) = cv::Vec3b(rgb[2], rgb[1], rgb[0]);  // OpenCV stores BGR
        }
      }
      method_map_->write(picture);
    });
  parallel_invoke(files, 0);
  rows_ += rows;
}

nlohmann::json SolveOutputWriter::finish(const SolveResult& result, const fs::path& input,
                                         const nlohmann::json& extra) {
  if (!extra.is_object())
    fail("{}: summary extras must be a JSON object, got {}", dir_.string(), extra.type_name());
  if (rows_ != size_.height)
    fail("{}: {} of {} rows of the result given: the solve folder is not complete", dir_.string(), rows_,
         size_.height);
  if (!opened_) open(SolveResult{});
  const auto commit = [&](RowWriter& writer) {
    writer.commit();
    committed_.push_back(writer.path());
  };
  for (auto* writer : {&normal_png_, &normal_vis_, &albedo_pfm_, &residual_pfm_, &normal_exr_, &albedo_exr_,
                       &colour_pfm_, &colour_exr_, &confidence_pfm_, &method_map_})
    if (*writer) commit(**writer);
  for (const auto& writer : coefficient_pfms_) commit(*writer);

  // The PNGs' whites, from the float maps just written, then the PNGs.
  const auto white = [&](BandQuantile& quantile, const fs::path& file, int channels) {
    if (!quantile.locate(kPngWhite)) return 1.0;
    read_back(file, [&](const cv::Mat& rows, int y0) {
      for (int y = 0; y < rows.rows; ++y) {
        const auto* solved = solved_.ptr<std::uint8_t>(y0 + y);
        for (int x = 0; x < rows.cols; ++x)
          if (solved[x] != 0)
            quantile.gather(rows.ptr<float>(y) + channels * x, static_cast<std::size_t>(channels));
      }
    });
    const double value = quantile.value();
    return std::isfinite(value) && value > 0 ? value : 1.0;
  };
  const auto write_png16_of = [&](const fs::path& file, const fs::path& png, int channels, double scale) {
    auto writer = open_png_writer(png, size_, CV_MAKETYPE(CV_16U, channels));
    read_back(file, [&](const cv::Mat& rows, int) { writer->write(png16(rows, scale)); });
    return writer;
  };
  // The grey and colour PNGs side by side (each reads back its own float map), committed in order after.
  double scale = 1, colour_scale = 1;
  std::unique_ptr<RowWriter> albedo_png, colour_png;
  std::vector<std::function<void()>> pngs;
  pngs.emplace_back([&] {
    scale = white(albedo_white_, dir_ / "albedo.pfm", 1);
    albedo_png = write_png16_of(dir_ / "albedo.pfm", dir_ / "albedo.png", 1, scale);
  });
  if (colour_)
    pngs.emplace_back([&] {
      colour_scale = white(colour_white_, dir_ / "albedo_rgb.pfm", 3);
      colour_png = write_png16_of(dir_ / "albedo_rgb.pfm", dir_ / "albedo_rgb.png", 3, colour_scale);
    });
  parallel_invoke(pngs, 0);
  commit(*albedo_png);
  if (colour_png) commit(*colour_png);

  nlohmann::json summary = result.summary.to_json();
  summary["parameters"] = result.parameters;
  summary["time"] = util::utc_timestamp();
  summary["input"] = input.string();
  summary["software"] = std::string("lightstage ") + kVersion;
  summary["width"] = size_.width;
  summary["height"] = size_.height;
  summary["albedo_png_scale"] = scale;
  summary["files"] = {{"normals", "normal.png"},    {"normals_visualisation", "normal_vis.png"},
                      {"albedo", "albedo.png"},     {"albedo_float", "albedo.pfm"},
                      {"residual", "residual.pfm"}, {"normals_exr", "normal.exr"},
                      {"albedo_exr", "albedo.exr"}};
  if (colour_) {
    summary["albedo_rgb_png_scale"] = colour_scale;
    summary["files"]["albedo_colour"] = "albedo_rgb.png";
    summary["files"]["albedo_colour_float"] = "albedo_rgb.pfm";
    summary["files"]["albedo_colour_exr"] = "albedo_rgb.exr";
  }
  if (confidence_pfm_) summary["files"]["confidence"] = "confidence.pfm";
  if (!coefficient_files_.empty()) summary["files"]["brdf"] = coefficient_files_;
  if (method_map_) {
    nlohmann::json legend = nlohmann::json::array();
    for (std::size_t k = 0; k < choice_counts_.size(); ++k) {
      const auto& rgb = kChoiceColours[k];
      legend.push_back({{"method", choices_[k]},
                        {"pixels", choice_counts_[k]},
                        {"colour", fmt::format("#{:02x}{:02x}{:02x}", rgb[0], rgb[1], rgb[2])}});
    }
    summary["method_map"] = {{"file", "method_map.png"}, {"choices", legend}};
    summary["files"]["method_map"] = "method_map.png";
  }
  if (!result.reflectance.is_null()) summary["reflectance"] = result.reflectance;
  for (const auto& [key, value] : extra.items()) summary[key] = value;
  util::write_text_atomic(dir_ / "summary.json", summary.dump(2) + "\n");
  finished_ = true;
  return summary;
}

nlohmann::json write_solve_outputs(const fs::path& dir, const SolveResult& result, const fs::path& input,
                                   const nlohmann::json& extra) {
  if (result.normals.empty())
    fail("{}: cannot write solver outputs: result maps are missing or of the wrong type/size", dir.string());
  if (!extra.is_object())
    fail("{}: summary extras must be a JSON object, got {}", dir.string(), extra.type_name());
  SolveOutputWriter writer(dir, result.normals.size());
  writer.add(result);
  return writer.finish(result, input, extra);
}

}  // namespace lightstage::io
