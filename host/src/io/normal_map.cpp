#include "lightstage/host/io/normal_map.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/io/image_io.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace lightstage::io {
namespace {

void check_inputs(const cv::Mat& normals, const cv::Mat& mask, const char* what) {
  if (normals.type() != CV_32FC3)
    fail("{}: normals must be CV_32FC3 (x, y, z), got type {}", what, normals.type());
  if (!mask.empty() && (mask.type() != CV_8UC1 || mask.size() != normals.size())) {
    fail("{}: mask must be CV_8UC1 of size {}x{}, got type {} size {}x{}", what, normals.cols, normals.rows,
         mask.type(), mask.cols, mask.rows);
  }
}

// Unit normal at (row, col) if inside the mask and usable.
bool unit_normal(const cv::Mat& normals, const cv::Mat& mask, int row, int col, cv::Vec3f& n) {
  if (!mask.empty() && mask.at<std::uint8_t>(row, col) == 0) return false;
  n = normals.at<cv::Vec3f>(row, col);
  const float length = std::sqrt(n.dot(n));
  if (!std::isfinite(length) || length <= 1e-12f) return false;
  n /= length;
  return true;
}

template <typename T>
cv::Mat encode(const cv::Mat& normals, const cv::Mat& mask, double full_scale) {
  cv::Mat encoded(normals.size(), CV_MAKETYPE(cv::DataType<T>::depth, 3), cv::Scalar::all(0));
  for (int row = 0; row < normals.rows; ++row) {
    auto* out = encoded.ptr<cv::Vec<T, 3>>(row);
    for (int col = 0; col < normals.cols; ++col) {
      cv::Vec3f n;
      if (!unit_normal(normals, mask, row, col, n)) continue;
      for (int c = 0; c < 3; ++c) {
        const double value = std::round((static_cast<double>(n[c]) + 1.0) / 2.0 * full_scale);
        // BGR: channel 2 is red = x.
        out[col][2 - c] = static_cast<T>(std::clamp(value, 0.0, full_scale));
      }
      // A normal that would encode as all zero cannot exist (it is not unit),
      // but keep "all zero = invalid" true under rounding anyway.
      if (out[col][0] == 0 && out[col][1] == 0 && out[col][2] == 0) out[col][0] = 1;
    }
  }
  return encoded;
}

}  // namespace

cv::Mat encode_normal_map(const cv::Mat& normals, const cv::Mat& mask) {
  check_inputs(normals, mask, "encode_normal_map");
  return encode<std::uint16_t>(normals, mask, 65535.0);
}

DecodedNormals decode_normal_map(const cv::Mat& encoded, const std::string& source) {
  if (encoded.channels() != 3 || (encoded.depth() != CV_16U && encoded.depth() != CV_8U)) {
    fail("{}: a normal map must be a 16-bit (or 8-bit) RGB image, got {} channel(s) of depth code {}", source,
         encoded.channels(), encoded.depth());
  }
  cv::Mat wide;
  const double full_scale = encoded.depth() == CV_16U ? 65535.0 : 255.0;
  encoded.convertTo(wide, CV_32FC3);
  DecodedNormals decoded;
  decoded.normals = cv::Mat(encoded.size(), CV_32FC3, cv::Scalar::all(0));
  decoded.valid = cv::Mat(encoded.size(), CV_8UC1, cv::Scalar::all(0));
  for (int row = 0; row < wide.rows; ++row) {
    const auto* in = wide.ptr<cv::Vec3f>(row);
    auto* out = decoded.normals.ptr<cv::Vec3f>(row);
    auto* valid = decoded.valid.ptr<std::uint8_t>(row);
    for (int col = 0; col < wide.cols; ++col) {
      const cv::Vec3f& bgr = in[col];
      if (bgr[0] == 0 && bgr[1] == 0 && bgr[2] == 0) continue;
      cv::Vec3d n;
      for (int c = 0; c < 3; ++c) n[c] = static_cast<double>(bgr[2 - c]) / full_scale * 2.0 - 1.0;
      const double length = std::sqrt(n.dot(n));
      if (length < 1e-6) continue;
      out[col] = cv::Vec3f(static_cast<float>(n[0] / length), static_cast<float>(n[1] / length),
                           static_cast<float>(n[2] / length));
      valid[col] = 255;
    }
  }
  return decoded;
}

void write_normal_map(const std::filesystem::path& path, const cv::Mat& normals, const cv::Mat& mask) {
  check_inputs(normals, mask, path.string().c_str());
  write_png16(path, encode<std::uint16_t>(normals, mask, 65535.0));
}

DecodedNormals read_normal_map(const std::filesystem::path& path) {
  return decode_normal_map(read_image(path), path.string());
}

cv::Mat normal_visualisation(const cv::Mat& normals, const cv::Mat& mask) {
  check_inputs(normals, mask, "normal_visualisation");
  cv::Mat picture = encode<std::uint8_t>(normals, mask, 255.0);
  return picture;
}

void write_normal_visualisation(const std::filesystem::path& path, const cv::Mat& normals,
                                const cv::Mat& mask) {
  check_inputs(normals, mask, path.string().c_str());
  write_png(path, encode<std::uint8_t>(normals, mask, 255.0));
}

}  // namespace lightstage::io
