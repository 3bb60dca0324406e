#include "report/maps.hpp"

#include "lightstage/common/error.hpp"

#include <algorithm>
#include <cmath>

namespace lightstage::report {

namespace {

void check_map(const cv::Mat& values, const cv::Mat& valid, int type, const char* what) {
  if (values.type() != type) fail("report: {} map has type {}, expected {}", what, values.type(), type);
  if (!valid.empty() && (valid.type() != CV_8UC1 || valid.size() != values.size()))
    fail("report: {} map's validity mask does not match it ({}x{})", what, values.cols, values.rows);
}

bool is_valid(const cv::Mat& valid, int y, int x) {
  return valid.empty() || valid.at<std::uint8_t>(y, x) != 0;
}

}  // namespace

std::vector<cv::Vec3b> colormap_samples(int colormap, int count) {
  cv::Mat ramp(1, std::max(count, 2), CV_8UC1);
  for (int i = 0; i < ramp.cols; ++i)
    ramp.at<std::uint8_t>(0, i) = cv::saturate_cast<std::uint8_t>(std::lround(255.0 * i / (ramp.cols - 1)));
  cv::Mat colours;
  cv::applyColorMap(ramp, colours, colormap);
  std::vector<cv::Vec3b> out;
  for (int i = 0; i < count; ++i) out.push_back(colours.at<cv::Vec3b>(0, i));
  return out;
}

cv::Mat false_colour(const cv::Mat& values, const cv::Mat& valid, double low, double high, int colormap) {
  check_map(values, valid, CV_32FC1, "false-colour");
  const double span = high > low ? high - low : 1.0;
  cv::Mat index(values.size(), CV_8UC1, cv::Scalar(0));
  for (int y = 0; y < values.rows; ++y) {
    for (int x = 0; x < values.cols; ++x) {
      const double v = (values.at<float>(y, x) - low) / span;
      index.at<std::uint8_t>(y, x) =
          std::isfinite(v) ? cv::saturate_cast<std::uint8_t>(std::lround(255.0 * std::clamp(v, 0.0, 1.0)))
                           : 0;
    }
  }
  cv::Mat colours;
  cv::applyColorMap(index, colours, colormap);
  cv::Mat out(values.size(), CV_8UC4, cv::Scalar(0, 0, 0, 0));
  for (int y = 0; y < values.rows; ++y) {
    for (int x = 0; x < values.cols; ++x) {
      if (!is_valid(valid, y, x) || !std::isfinite(values.at<float>(y, x))) continue;
      const auto c = colours.at<cv::Vec3b>(y, x);
      out.at<cv::Vec4b>(y, x) = {c[0], c[1], c[2], 255};
    }
  }
  return out;
}

cv::Mat normal_colours(const cv::Mat& normals, const cv::Mat& valid) {
  check_map(normals, valid, CV_32FC3, "normal");
  cv::Mat out(normals.size(), CV_8UC4, cv::Scalar(0, 0, 0, 0));
  const auto code = [](float v) {
    return cv::saturate_cast<std::uint8_t>(std::lround((std::clamp(v, -1.0f, 1.0f) + 1.0) / 2.0 * 255.0));
  };
  for (int y = 0; y < normals.rows; ++y) {
    for (int x = 0; x < normals.cols; ++x) {
      const auto n = normals.at<cv::Vec3f>(y, x);
      if (!is_valid(valid, y, x) || (n[0] == 0 && n[1] == 0 && n[2] == 0)) continue;
      out.at<cv::Vec4b>(y, x) = {code(n[2]), code(n[1]), code(n[0]), 255};  // BGRA: blue = z, red = x
    }
  }
  return out;
}

cv::Mat normal_sphere_legend(int size) {
  cv::Mat normals(size, size, CV_32FC3, cv::Scalar(0, 0, 0));
  const double r = size / 2.0 - 1.0;
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const double nx = (x + 0.5 - size / 2.0) / r, ny = -(y + 0.5 - size / 2.0) / r;
      const double r2 = nx * nx + ny * ny;
      if (r2 > 1) continue;
      normals.at<cv::Vec3f>(y, x) =
          cv::Vec3f(static_cast<float>(nx), static_cast<float>(ny), static_cast<float>(std::sqrt(1 - r2)));
    }
  }
  return normal_colours(normals, {});
}

cv::Mat grey(const cv::Mat& values, const cv::Mat& valid, double scale) {
  const bool colour = values.type() == CV_32FC3;
  check_map(values, valid, colour ? CV_32FC3 : CV_32FC1, "grey");
  const double s = scale > 0 ? scale : 1.0;
  const auto byte = [s](float v) {
    return cv::saturate_cast<std::uint8_t>(std::lround(255.0 * std::clamp(v / s, 0.0, 1.0)));
  };
  cv::Mat out(values.size(), CV_8UC4, cv::Scalar(0, 0, 0, 0));
  for (int y = 0; y < values.rows; ++y) {
    for (int x = 0; x < values.cols; ++x) {
      if (!is_valid(valid, y, x)) continue;
      if (colour) {
        const cv::Vec3f v = values.at<cv::Vec3f>(y, x);
        if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) continue;
        out.at<cv::Vec4b>(y, x) = {byte(v[0]), byte(v[1]), byte(v[2]), 255};
      } else {
        const float v = values.at<float>(y, x);
        if (!std::isfinite(v)) continue;
        const auto g = byte(v);
        out.at<cv::Vec4b>(y, x) = {g, g, g, 255};
      }
    }
  }
  return out;
}

cv::Mat shaded_depth(const cv::Mat& depth, const cv::Mat& valid, double pixel_size) {
  check_map(depth, valid, CV_32FC1, "depth");
  const double step = pixel_size > 0 ? pixel_size : 1.0;
  const auto ok = [&](int y, int x) {
    return y >= 0 && x >= 0 && y < depth.rows && x < depth.cols && is_valid(valid, y, x) &&
           std::isfinite(depth.at<float>(y, x));
  };
  // The light: from the upper left, toward the camera (x right, y up, z to the camera).
  const cv::Vec3d light = cv::normalize(cv::Vec3d(-1, 1, 1.5));
  cv::Mat out(depth.size(), CV_8UC4, cv::Scalar(0, 0, 0, 0));
  for (int y = 0; y < depth.rows; ++y) {
    for (int x = 0; x < depth.cols; ++x) {
      if (!ok(y, x)) continue;
      const double z = depth.at<float>(y, x);
      // One-sided differences at the object's edge. Row index grows downward, y upward.
      const double right =
          ok(y, x + 1) ? depth.at<float>(y, x + 1) - z : (ok(y, x - 1) ? z - depth.at<float>(y, x - 1) : 0);
      const double up =
          ok(y - 1, x) ? depth.at<float>(y - 1, x) - z : (ok(y + 1, x) ? z - depth.at<float>(y + 1, x) : 0);
      const cv::Vec3d n = cv::normalize(cv::Vec3d(-right / step, -up / step, 1.0));
      const double shade = 0.12 + 0.88 * std::max(0.0, n.dot(light));
      const auto g = cv::saturate_cast<std::uint8_t>(std::lround(255.0 * std::min(shade, 1.0)));
      out.at<cv::Vec4b>(y, x) = {g, g, g, 255};
    }
  }
  return out;
}

double nice_ceiling(double value) {
  if (!(value > 0) || !std::isfinite(value)) return 1.0;
  const double power = std::pow(10.0, std::floor(std::log10(value)));
  for (const double m : {1.0, 2.0, 2.5, 5.0, 10.0})
    if (m * power >= value * (1 - 1e-12)) return m * power;
  return 10 * power;
}

}  // namespace lightstage::report
