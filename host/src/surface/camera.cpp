#include "lightstage/host/surface/camera.hpp"

#include "lightstage/common/error.hpp"

#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>
#include <vector>

namespace lightstage::surface {

CameraModel CameraModel::orthographic(cv::Size size, double pixel_size) {
  CameraModel m;
  m.kind = Kind::kOrthographic;
  m.size = size;
  m.pixel_size = pixel_size;
  m.check();
  return m;
}

CameraModel CameraModel::perspective(cv::Size size, const Mat3& K) {
  CameraModel m;
  m.kind = Kind::kPerspective;
  m.size = size;
  m.K = K;
  m.check();
  return m;
}

Vec3 CameraModel::point(double col, double row, double depth) const {
  if (kind == Kind::kOrthographic) {
    const double cx = (size.width - 1) / 2.0, cy = (size.height - 1) / 2.0;
    return {(col - cx) * pixel_size, -(row - cy) * pixel_size, depth};
  }
  return depth * Vec3((col - K(0, 2)) / K(0, 0), -(row - K(1, 2)) / K(1, 1), -1.0);
}

bool CameraModel::project(const Vec3& p, double* col, double* row, double* depth) const {
  if (kind == Kind::kOrthographic) {
    const double cx = (size.width - 1) / 2.0, cy = (size.height - 1) / 2.0;
    *col = p.x() / pixel_size + cx;
    *row = -p.y() / pixel_size + cy;
    *depth = p.z();
    return true;
  }
  const double d = -p.z();
  if (!(d > 0)) return false;
  *col = K(0, 0) * p.x() / d + K(0, 2);
  *row = -K(1, 1) * p.y() / d + K(1, 2);
  *depth = d;
  return true;
}

void CameraModel::check() const {
  if (size.width <= 0 || size.height <= 0)
    fail("camera model: image size must be positive, got {}x{}", size.width, size.height);
  if (kind == Kind::kOrthographic) {
    if (!(pixel_size > 0) || !std::isfinite(pixel_size))
      fail("camera model: pixel size must be positive, got {}", pixel_size);
    return;
  }
  if (!K.allFinite()) fail("camera model: intrinsics must be finite");
  if (!(K(0, 0) > 0) || !(K(1, 1) > 0))
    fail("camera model: intrinsics fx, fy must be positive, got {}, {}", K(0, 0), K(1, 1));
}

Mat3 parse_intrinsics(const std::string& text, const std::string& source) {
  std::vector<double> values;
  std::size_t pos = 0;
  auto separator = [](char ch) {
    return std::isspace(static_cast<unsigned char>(ch)) || ch == ',' || ch == ';' || ch == '[' || ch == ']';
  };
  while (pos < text.size()) {
    while (pos < text.size() && separator(text[pos])) ++pos;
    if (pos >= text.size()) break;
    std::size_t end = pos;
    while (end < text.size() && !separator(text[end])) ++end;
    const std::string token = text.substr(pos, end - pos);
    double v = 0;
    const auto [next, error] = std::from_chars(token.data(), token.data() + token.size(), v);
    if (error != std::errc() || next != token.data() + token.size() || !std::isfinite(v))
      fail("{}: intrinsics: '{}' is not a finite number", source, token.substr(0, 40));
    if (values.size() == 9) fail("{}: intrinsics: more than nine numbers (a 3x3 matrix)", source);
    values.push_back(v);
    pos = end;
  }
  if (values.size() != 9)
    fail("{}: intrinsics: expected nine numbers (a 3x3 matrix), got {}", source, values.size());
  Mat3 K;
  for (int i = 0; i < 9; ++i) K(i / 3, i % 3) = values[static_cast<std::size_t>(i)];
  if (!(K(0, 0) > 0) || !(K(1, 1) > 0))
    fail("{}: intrinsics: fx and fy (K[0][0], K[1][1]) must be positive, got {} and {}", source, K(0, 0),
         K(1, 1));
  if (K(2, 0) != 0 || K(2, 1) != 0 || K(2, 2) != 1)
    fail("{}: intrinsics: the last row must be 0 0 1, got {} {} {}", source, K(2, 0), K(2, 1), K(2, 2));
  return K;
}

Mat3 read_intrinsics(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("{}: cannot open intrinsics file", path.string());
  std::ostringstream text;
  text << in.rdbuf();
  if (text.str().size() > (1 << 16)) fail("{}: intrinsics file is too large for a 3x3 matrix", path.string());
  return parse_intrinsics(text.str(), path.string());
}

}  // namespace lightstage::surface
