#include "lightstage/host/io/relight_web.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/jpeg_image.hpp"
#include "lightstage/host/io/output_folder.hpp"

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <sstream>

namespace lightstage::io {
namespace {

// relight's term k is our term order()[k]. PTM: relight evaluates
// 1, x, y, x², xy, y²; ours (the .ptm order) is x², y², xy, x, y, 1.
// HSH: the same order in both.
std::vector<int> term_order(RtiBasis basis) {
  if (basis == RtiBasis::ptm) return {5, 3, 4, 0, 2, 1};
  std::vector<int> order(static_cast<std::size_t>(rti_term_count(basis)));
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = static_cast<int>(k);
  return order;
}

std::string plane_name(int image, const std::string& format) {
  return fmt::format("plane_{}.{}", image, format);
}

std::uint8_t quantise(double a, double scale, double bias) {
  return static_cast<std::uint8_t>(std::clamp(std::lround(255.0 * (a / scale + bias)), 0L, 255L));
}

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("{}: cannot open (a relight folder holds info.json)", path.string());
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

void RelightWebOptions::check() const {
  if (colorspace != "lrgb" && colorspace != "rgb") fail("--colour: '{}' is not lrgb or rgb", colorspace);
  if (image_format != "jpg" && image_format != "png") fail("--planes: '{}' is not jpg or png", image_format);
  if (quality < 1 || quality > 100) fail("--quality: {} is not in 1..100", quality);
}

nlohmann::json write_relight_web(const std::filesystem::path& dir, const RtiImage& image,
                                 const RelightWebOptions& options) {
  options.check();
  const int terms = rti_term_count(image.basis);
  const int n = image.width * image.height;
  if (image.width <= 0 || image.height <= 0)
    fail("relight export: size {}x{} is empty", image.width, image.height);
  for (const auto& c : image.channels)
    if (c.rows() != n || c.cols() != terms)
      fail("relight export: a channel is {}x{}, expected {}x{}", c.rows(), c.cols(), n, terms);
  require_empty_folder(dir, "--out", "choose a new --out folder");
  const std::vector<int> order = term_order(image.basis);

  // Planes in relight's order, each n values in our units, and whether it is
  // a colour plane (lrgb planes 0..2: bytes = colour · 255, scale 1, bias 0).
  std::vector<Eigen::VectorXf> planes;
  std::vector<bool> colour;
  if (options.colorspace == "lrgb") {
    const LrgbSplit split = split_lrgb(image);
    for (int c = 0; c < 3; ++c) {
      planes.emplace_back(split.rgb.col(c));
      colour.push_back(true);
    }
    for (const int k : order) {
      planes.emplace_back(split.lum.col(k));
      colour.push_back(false);
    }
  } else {
    for (const int k : order)
      for (int c = 0; c < 3; ++c) {
        planes.emplace_back(image.channels[c].col(k));
        colour.push_back(false);
      }
  }
  const int nplanes = static_cast<int>(planes.size());
  std::vector<double> scale(planes.size(), 1.0), bias(planes.size(), 0.0);
  for (std::size_t p = 0; p < planes.size(); ++p) {
    if (colour[p]) continue;
    // Each plane its own range: byte 0 is the plane's minimum, 255 its maximum.
    const double lo = planes[p].minCoeff(), hi = planes[p].maxCoeff();
    scale[p] = std::max(hi - lo, 1e-12);
    bias[p] = -lo / scale[p];
  }

  std::filesystem::create_directories(dir);
  const int images = (nplanes + 2) / 3;
  std::vector<std::string> files;
  for (int j = 0; j < images; ++j) {
    cv::Mat out(image.height, image.width, CV_8UC3, cv::Scalar::all(0));
    for (int c = 0; c < 3; ++c) {
      const int p = 3 * j + c;
      if (p >= nplanes) break;
      for (int i = 0; i < n; ++i)
        // OpenCV holds the image as BGR: plane 3j + c (R, G, B) is channel 2 − c.
        out.ptr<cv::Vec3b>(i / image.width)[i % image.width][2 - c] =
            quantise(planes[p](i), scale[p], bias[p]);
    }
    const std::string name = plane_name(j, options.image_format);
    const std::filesystem::path file = dir / name;
    if (options.image_format == "png")
      write_png(file, out);
    else
      write_jpeg(file, out, options.quality);
    files.push_back(name);
  }
  nlohmann::json info = {{"width", image.width},
                         {"height", image.height},
                         {"format", options.image_format},
                         {"type", image.basis == RtiBasis::ptm ? "ptm" : "hsh"},
                         {"colorspace", options.colorspace},
                         {"nplanes", nplanes},
                         {"quality", options.quality},
                         {"materials", nlohmann::json::array({{{"scale", scale}, {"bias", bias}}})}};
  const std::filesystem::path info_file = dir / "info.json";
  std::ofstream json(info_file);
  json << info.dump(1) << "\n";
  if (!json) fail("{}: cannot write", info_file.string());
  return info;
}

RelightInfo parse_relight_info(const std::string& text, const std::string& source) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    fail("{}: not JSON ({})", source, e.what());
  }
  if (!j.is_object()) fail("{}: not a JSON object", source);
  auto integer = [&](const char* key, int lo, int hi) {
    const auto it = j.find(key);
    if (it == j.end()) fail("{}: {}: missing", source, key);
    if (!it->is_number_integer()) fail("{}: {}: not an integer", source, key);
    const auto v = it->get<long long>();
    if (v < lo || v > hi) fail("{}: {}: {} is outside {}..{}", source, key, v, lo, hi);
    return static_cast<int>(v);
  };
  auto string = [&](const char* key, const char* fallback) {
    const auto it = j.find(key);
    if (it == j.end()) {
      if (fallback != nullptr) return std::string(fallback);
      fail("{}: {}: missing", source, key);
    }
    if (!it->is_string()) fail("{}: {}: not a string", source, key);
    return it->get<std::string>();
  };
  RelightInfo info;
  info.width = integer("width", 1, kMaxRtiSide);
  info.height = integer("height", 1, kMaxRtiSide);
  info.type = string("type", nullptr);
  if (info.type != "ptm" && info.type != "hsh")
    fail("{}: type: '{}' is not ptm or hsh (the bases read here)", source, info.type.substr(0, 40));
  info.colorspace = string("colorspace", nullptr);
  if (info.colorspace != "rgb" && info.colorspace != "lrgb")
    fail("{}: colorspace: '{}' is not rgb or lrgb (the colour spaces read here)", source,
         info.colorspace.substr(0, 40));
  info.format = string("format", "jpg");
  if (info.format != "jpg" && info.format != "png")
    fail("{}: format: '{}' is not jpg or png", source, info.format.substr(0, 40));
  info.nplanes = integer("nplanes", 1, 1000);
  const bool rgb = info.colorspace == "rgb";
  if (rgb && info.nplanes % 3 != 0)
    fail("{}: nplanes: {} is not a multiple of 3 (rgb)", source, info.nplanes);
  const int terms = rgb ? info.nplanes / 3 : info.nplanes - 3;
  if (info.type == "ptm" && terms == 6)
    info.basis = RtiBasis::ptm;
  else if (info.type == "hsh" && terms == 4)
    info.basis = RtiBasis::hsh2;
  else if (info.type == "hsh" && terms == 9)
    info.basis = RtiBasis::hsh3;
  else
    fail("{}: nplanes: {} planes give {} {} terms ({}: 6 for ptm, 4 or 9 for hsh)", source, info.nplanes,
         terms, info.type, rgb ? "nplanes / 3" : "nplanes - 3");
  const auto mats = j.find("materials");
  if (mats == j.end() || !mats->is_array() || mats->empty())
    fail("{}: materials: missing or not a non-empty array", source);
  if (mats->size() > 1)
    fail("{}: materials: {} materials (segmented RTI) are not read", source, mats->size());
  const auto& m = (*mats)[0];
  if (!m.is_object()) fail("{}: materials[0]: not an object", source);
  auto numbers = [&](const char* key) {
    const auto it = m.find(key);
    if (it == m.end() || !it->is_array()) fail("{}: materials[0].{}: missing or not an array", source, key);
    if (it->size() != static_cast<std::size_t>(info.nplanes))
      fail("{}: materials[0].{}: {} values for {} planes", source, key, it->size(), info.nplanes);
    std::vector<double> v;
    for (const auto& x : *it) {
      if (!x.is_number()) fail("{}: materials[0].{}: a value is not a number", source, key);
      v.push_back(x.get<double>());
      if (!std::isfinite(v.back())) fail("{}: materials[0].{}: a value is not finite", source, key);
    }
    return v;
  };
  info.scale = numbers("scale");
  info.bias = numbers("bias");
  return info;
}

RtiImage read_relight_web(const std::filesystem::path& dir) {
  const std::filesystem::path info_file = dir / "info.json";
  const RelightInfo info = parse_relight_info(read_text(info_file), info_file.string());
  const int n = info.width * info.height;
  std::vector<Eigen::VectorXf> planes(static_cast<std::size_t>(info.nplanes), Eigen::VectorXf(n));
  for (int j = 0; j < info.image_count(); ++j) {
    const std::filesystem::path file = dir / plane_name(j, info.format);
    if (!std::filesystem::is_regular_file(file))
      fail("{}: missing (info.json has {} planes)", file.string(), info.nplanes);
    cv::Mat img = read_image(file);
    if (img.depth() != CV_8U)
      fail("{}: {}-bit samples; relight planes are 8-bit", file.string(), img.elemSize1() * 8);
    if (img.channels() == 1) cv::cvtColor(img, img, cv::COLOR_GRAY2BGR);
    if (img.cols != info.width || img.rows != info.height)
      fail("{}: {}x{}, info.json says {}x{}", file.string(), img.cols, img.rows, info.width, info.height);
    for (int c = 0; c < 3; ++c) {
      const auto p = static_cast<std::size_t>(3 * j + c);
      if (p >= planes.size()) break;
      for (int i = 0; i < n; ++i) {
        const double byte = img.ptr<cv::Vec3b>(i / info.width)[i % info.width][2 - c];
        planes[p](i) = static_cast<float>((byte / 255.0 - info.bias[p]) * info.scale[p]);
      }
    }
  }
  RtiImage image;
  image.basis = info.basis;
  image.width = info.width;
  image.height = info.height;
  const std::vector<int> order = term_order(info.basis);
  const int terms = static_cast<int>(order.size());
  for (auto& c : image.channels) c.resize(n, terms);
  for (int k = 0; k < terms; ++k)
    for (int c = 0; c < 3; ++c) {
      if (info.colorspace == "rgb")
        image.channels[c].col(order[k]) = planes[static_cast<std::size_t>(3 * k + c)];
      else  // colour (planes 0..2, dequantised as relight.js does) times luminance
        image.channels[c].col(order[k]) =
            planes[static_cast<std::size_t>(3 + k)].cwiseProduct(planes[static_cast<std::size_t>(c)]);
    }
  return image;
}

}  // namespace lightstage::io
