#include "lightstage/host/io/rti_files.hpp"

#include "lightstage/common/error.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>

namespace lightstage::io {
namespace {

int pixel_count(const RtiImage& image) { return image.width * image.height; }

// PTM stores rows bottom to top: file pixel i is image pixel at this index.
// (HSH .rti stores them top to bottom: docs/rti-formats.md.)
int image_index(int file_pixel, int width, int height) {
  const int row = file_pixel / width;
  const int col = file_pixel % width;
  return (height - 1 - row) * width + col;
}

void check_image(const RtiImage& image, int terms) {
  if (image.width <= 0 || image.height <= 0)
    fail("RTI image: size {}x{} is empty", image.width, image.height);
  for (const auto& c : image.channels)
    if (c.rows() != pixel_count(image) || c.cols() != terms)
      fail("RTI image: a channel is {}x{}, expected {}x{}", c.rows(), c.cols(), pixel_count(image), terms);
}

std::string read_all(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("{}: cannot open", path.string());
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void write_all(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out) fail("{}: cannot write", path.string());
}

// A cursor over the text header and the bytes after it.
struct Reader {
  const std::string& bytes;
  const std::string& source;
  std::size_t pos = 0;

  std::string line(const char* field) {
    const std::size_t end = bytes.find('\n', pos);
    if (end == std::string::npos) fail("{}: {}: missing (file ends in the header)", source, field);
    std::string text = bytes.substr(pos, end - pos);
    pos = end + 1;
    while (!text.empty() && (text.back() == '\r' || text.back() == ' ')) text.pop_back();
    return text;
  }
  template <typename T>
  std::vector<T> numbers(const char* field, std::size_t count) {
    std::istringstream in(line(field));
    std::vector<T> v(count);
    for (auto& x : v)
      if (!(in >> x)) fail("{}: {}: expected {} numbers", source, field, count);
    for (auto x : v)
      if (!std::isfinite(static_cast<double>(x))) fail("{}: {}: a value is not finite", source, field);
    return v;
  }
  const unsigned char* take(std::size_t count, const char* field) {
    if (bytes.size() - pos < count)
      fail("{}: {}: {} bytes expected, {} left", source, field, count, bytes.size() - pos);
    const auto* p = reinterpret_cast<const unsigned char*>(bytes.data() + pos);
    pos += count;
    return p;
  }
};

void check_size(int w, int h, const std::string& source) {
  if (w <= 0 || h <= 0 || w > kMaxRtiSide || h > kMaxRtiSide)
    fail("{}: size: {}x{} is outside 1..{}", source, w, h, kMaxRtiSide);
}

std::uint8_t clamp_byte(double v) { return static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L)); }

// ---- PTM ----

// Per-coefficient scale (float) and integer bias with a = (c - bias) · scale.
struct PtmQuant {
  std::array<float, 6> scale{};
  std::array<int, 6> bias{};
};

PtmQuant ptm_quant(const std::vector<const Eigen::MatrixXf*>& planes) {
  PtmQuant q;
  for (int k = 0; k < 6; ++k) {
    float lo = 0, hi = 0;
    for (const auto* p : planes) {
      lo = std::min(lo, p->col(k).minCoeff());
      hi = std::max(hi, p->col(k).maxCoeff());
    }
    // 0 is always in range, so the integer bias places it exactly.
    q.scale[k] = std::max((hi - lo) / 255.0f, 1e-12f);
    q.bias[k] = static_cast<int>(std::lround(-lo / q.scale[k]));
  }
  return q;
}

}  // namespace

LrgbSplit split_lrgb(const RtiImage& image) {
  check_image(image, rti_term_count(image.basis));
  const int n = pixel_count(image);
  const Eigen::VectorXf overhead = rti_weights(image.basis, Vec3::UnitZ()).cast<float>();
  LrgbSplit s;
  s.lum = (image.channels[0] + image.channels[1] + image.channels[2]) / 3.0f;
  s.rgb.resize(n, 3);
  for (int i = 0; i < n; ++i) {
    const float y = s.lum.row(i).dot(overhead);
    float peak = 0;
    for (int c = 0; c < 3; ++c) {
      s.rgb(i, c) = y > 0 ? std::max(image.channels[c].row(i).dot(overhead) / y, 0.0f) : 1.0f;
      peak = std::max(peak, s.rgb(i, c));
    }
    // The brightest channel at 1: the luminance model carries the scale.
    if (peak > 0) {
      s.rgb.row(i) /= peak;
      s.lum.row(i) *= peak;
    }
  }
  return s;
}

std::string format_ptm(const RtiImage& image, PtmFormat format) {
  if (image.basis != RtiBasis::ptm) fail("PTM export: the model is {}, not ptm", rti_basis_name(image.basis));
  check_image(image, 6);
  const int n = pixel_count(image);
  LrgbSplit split;
  if (format == PtmFormat::lrgb) split = split_lrgb(image);
  const Eigen::MatrixXf& lum = split.lum;
  const Eigen::MatrixX3f& rgb = split.rgb;
  std::vector<const Eigen::MatrixXf*> planes;
  if (format == PtmFormat::lrgb)
    planes = {&lum};
  else
    planes = {&image.channels[0], &image.channels[1], &image.channels[2]};
  const PtmQuant q = ptm_quant(planes);

  std::string out =
      fmt::format("PTM_1.2\n{}\n{} {}\n", format == PtmFormat::lrgb ? "PTM_FORMAT_LRGB" : "PTM_FORMAT_RGB",
                  image.width, image.height);
  for (int k = 0; k < 6; ++k) out += fmt::format("{}{:.9g}", k ? " " : "", q.scale[k]);
  out += "\n";
  for (int k = 0; k < 6; ++k) out += fmt::format("{}{}", k ? " " : "", q.bias[k]);
  out += "\n";
  auto put_coefficients = [&](const Eigen::MatrixXf& plane) {
    for (int f = 0; f < n; ++f) {
      const int i = image_index(f, image.width, image.height);
      for (int k = 0; k < 6; ++k)
        out.push_back(static_cast<char>(clamp_byte(plane(i, k) / q.scale[k] + q.bias[k])));
    }
  };
  for (const auto* p : planes) put_coefficients(*p);
  if (format == PtmFormat::lrgb)
    for (int f = 0; f < n; ++f) {
      const int i = image_index(f, image.width, image.height);
      for (int c = 0; c < 3; ++c) out.push_back(static_cast<char>(clamp_byte(rgb(i, c) * 255.0)));
    }
  return out;
}

void write_ptm(const std::filesystem::path& path, const RtiImage& image, PtmFormat format) {
  write_all(path, format_ptm(image, format));
}

RtiImage parse_ptm(const std::string& bytes, const std::string& source) {
  Reader r{bytes, source};
  if (r.line("header") != "PTM_1.2") fail("{}: header: not 'PTM_1.2'", source);
  const std::string kind = r.line("format");
  if (kind != "PTM_FORMAT_LRGB" && kind != "PTM_FORMAT_RGB")
    fail("{}: format: '{}' is not PTM_FORMAT_LRGB or PTM_FORMAT_RGB", source, kind.substr(0, 40));
  const auto size = r.numbers<long>("size", 2);
  check_size(static_cast<int>(std::clamp(size[0], -1L, 1L << 20)),
             static_cast<int>(std::clamp(size[1], -1L, 1L << 20)), source);
  const auto scale = r.numbers<float>("scale", 6);
  const auto bias = r.numbers<int>("bias", 6);
  RtiImage image;
  image.basis = RtiBasis::ptm;
  image.width = static_cast<int>(size[0]);
  image.height = static_cast<int>(size[1]);
  const int n = pixel_count(image);
  auto get_plane = [&](const char* field) {
    const unsigned char* p = r.take(static_cast<std::size_t>(n) * 6, field);
    Eigen::MatrixXf plane(n, 6);
    for (int f = 0; f < n; ++f) {
      const int i = image_index(f, image.width, image.height);
      for (int k = 0; k < 6; ++k) plane(i, k) = (static_cast<float>(p[f * 6 + k]) - bias[k]) * scale[k];
    }
    return plane;
  };
  if (kind == "PTM_FORMAT_RGB") {
    image.channels[0] = get_plane("red coefficients");
    image.channels[1] = get_plane("green coefficients");
    image.channels[2] = get_plane("blue coefficients");
    return image;
  }
  const Eigen::MatrixXf lum = get_plane("luminance coefficients");
  const unsigned char* p = r.take(static_cast<std::size_t>(n) * 3, "rgb");
  for (int c = 0; c < 3; ++c) image.channels[c].resize(n, 6);
  for (int f = 0; f < n; ++f) {
    const int i = image_index(f, image.width, image.height);
    for (int c = 0; c < 3; ++c) image.channels[c].row(i) = lum.row(i) * (p[f * 3 + c] / 255.0f);
  }
  return image;
}

RtiImage read_ptm(const std::filesystem::path& path) { return parse_ptm(read_all(path), path.string()); }

// ---- HSH ----

std::string format_hsh(const RtiImage& image) {
  if (image.basis == RtiBasis::ptm) fail("HSH export: the model is ptm, not hsh2 or hsh3");
  const int terms = rti_term_count(image.basis);
  check_image(image, terms);
  const int n = pixel_count(image);
  std::vector<float> scale(terms), bias(terms);
  for (int k = 0; k < terms; ++k) {
    float lo = image.channels[0].col(k).minCoeff(), hi = image.channels[0].col(k).maxCoeff();
    for (int c = 1; c < 3; ++c) {
      lo = std::min(lo, image.channels[c].col(k).minCoeff());
      hi = std::max(hi, image.channels[c].col(k).maxCoeff());
    }
    bias[k] = lo;
    scale[k] = std::max(hi - lo, 1e-12f);
  }
  std::string out =
      fmt::format("#HSH1.2\n#written by lightstage\n3\n{} {} 3\n{} 2 1\n", image.width, image.height, terms);
  auto put_floats = [&](const std::vector<float>& v) {
    for (float x : v) {
      char b[4];
      std::memcpy(b, &x, 4);  // little endian hosts only (x86-64, arm64)
      out.append(b, 4);
    }
  };
  put_floats(scale);
  put_floats(bias);
  for (int i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < terms; ++k)
        out.push_back(static_cast<char>(clamp_byte((image.channels[c](i, k) - bias[k]) / scale[k] * 255.0)));
  }
  return out;
}

void write_hsh(const std::filesystem::path& path, const RtiImage& image) {
  write_all(path, format_hsh(image));
}

RtiImage parse_hsh(const std::string& bytes, const std::string& source) {
  Reader r{bytes, source};
  std::string type = r.line("header");
  if (type.rfind("#HSH", 0) != 0) fail("{}: header: first line is not '#HSH1.2'", source);
  while (!type.empty() && type[0] == '#') type = r.line("type");
  if (type != "3") fail("{}: type: '{}' is not 3 (HSH)", source, type.substr(0, 40));
  const auto size = r.numbers<long>("size", 3);
  check_size(static_cast<int>(std::clamp(size[0], -1L, 1L << 20)),
             static_cast<int>(std::clamp(size[1], -1L, 1L << 20)), source);
  if (size[2] != 3) fail("{}: channels: {} is not 3", source, size[2]);
  const auto layout = r.numbers<long>("terms", 3);
  RtiImage image;
  if (layout[0] == 4)
    image.basis = RtiBasis::hsh2;
  else if (layout[0] == 9)
    image.basis = RtiBasis::hsh3;
  else
    fail("{}: terms: {} is not 4 or 9", source, layout[0]);
  if (layout[2] != 1) fail("{}: element size: {} is not 1 (byte)", source, layout[2]);
  const int terms = static_cast<int>(layout[0]);
  image.width = static_cast<int>(size[0]);
  image.height = static_cast<int>(size[1]);
  auto get_floats = [&](const char* field) {
    const unsigned char* p = r.take(static_cast<std::size_t>(terms) * 4, field);
    std::vector<float> v(terms);
    std::memcpy(v.data(), p, v.size() * 4);
    for (float x : v)
      if (!std::isfinite(x)) fail("{}: {}: a value is not finite", source, field);
    return v;
  };
  const auto scale = get_floats("scale");
  const auto bias = get_floats("bias");
  const int n = pixel_count(image);
  const unsigned char* p = r.take(static_cast<std::size_t>(n) * 3 * terms, "coefficients");
  for (auto& c : image.channels) c.resize(n, terms);
  for (int i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < terms; ++k)
        image.channels[c](i, k) = p[(i * 3 + c) * terms + k] / 255.0f * scale[k] + bias[k];
  }
  return image;
}

RtiImage read_hsh(const std::filesystem::path& path) { return parse_hsh(read_all(path), path.string()); }

}  // namespace lightstage::io
