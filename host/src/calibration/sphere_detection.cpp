#include "lightstage/host/calibration/sphere_detection.hpp"

#include "lightstage/common/error.hpp"

#include <Eigen/Dense>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace lightstage::calibration {
namespace {

double rms_distance(const std::vector<Vec2>& points, const Vec2& centre, double radius) {
  double sum = 0;
  for (const auto& p : points) {
    const double d = (p - centre).norm() - radius;
    sum += d * d;
  }
  return std::sqrt(sum / static_cast<double>(points.size()));
}

// Bilinear sample of a CV_32FC1 image at image point (u, v) (pixel centres at +0.5).
bool sample(const cv::Mat& image, double u, double v, double* value) {
  const double x = u - 0.5, y = v - 0.5;
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  if (x0 < 0 || y0 < 0 || x0 + 1 >= image.cols || y0 + 1 >= image.rows) return false;
  const double fx = x - x0, fy = y - y0;
  const auto* r0 = image.ptr<float>(y0);
  const auto* r1 = image.ptr<float>(y0 + 1);
  *value = (1 - fy) * ((1 - fx) * r0[x0] + fx * r0[x0 + 1]) + fy * ((1 - fx) * r1[x0] + fx * r1[x0 + 1]);
  return true;
}

double median_of(std::vector<double> values) {
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

std::string describe(const std::vector<ImageCircle>& circles) {
  std::string text;
  for (const auto& c : circles) {
    text += fmt::format("{}({:.1f}, {:.1f}) r {:.1f}", text.empty() ? "" : ", ", c.centre_px.x(),
                        c.centre_px.y(), c.radius_px);
  }
  return text;
}

void check_count(const std::vector<ImageCircle>& circles, const SphereDetectionOptions& options,
                 const std::string& what) {
  if (circles.empty()) {
    fail("{}: no sphere found (no circular blob of radius >= {} px); give its outline with --sphere U,V,R",
         what, options.min_radius_px);
  }
  if (static_cast<int>(circles.size()) != options.expected) {
    fail("{}: found {} spheres ({}), expected {}; give the outlines with --sphere U,V,R or set --spheres",
         what, circles.size(), describe(circles), options.expected);
  }
}

}  // namespace

nlohmann::json ImageCircle::to_json() const {
  return {{"centre_px", {centre_px.x(), centre_px.y()}},
          {"radius_px", radius_px},
          {"rms_px", rms_px},
          {"edge_points", edge_points},
          {"source", source}};
}

void SphereDetectionOptions::check() const {
  if (expected < 1 || expected > 16)
    fail("SphereDetectionOptions.expected: must be in 1..16, got {}", expected);
  if (!(min_radius_px >= 2))
    fail("SphereDetectionOptions.min_radius_px: must be at least 2, got {}", min_radius_px);
  if (!(max_rms_px > 0)) fail("SphereDetectionOptions.max_rms_px: must be positive, got {}", max_rms_px);
  if (profiles < 16) fail("SphereDetectionOptions.profiles: must be at least 16, got {}", profiles);
}

ImageCircle fit_circle(const std::vector<Vec2>& points) {
  if (points.size() < 3) fail("circle fit: {} point(s), at least 3 needed", points.size());
  // Kåsa: x² + y² + D x + E y + F = 0, linear least squares (centred for conditioning).
  Vec2 mean = Vec2::Zero();
  for (const auto& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Eigen::MatrixXd a(static_cast<Eigen::Index>(points.size()), 3);  // dynamic: thin SVD needs it
  Eigen::VectorXd b(static_cast<Eigen::Index>(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec2 p = points[i] - mean;
    const auto row = static_cast<Eigen::Index>(i);
    a.row(row) << p.x(), p.y(), 1.0;
    b(row) = -(p.squaredNorm());
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::Vector3d sv = svd.singularValues();
  if (!(sv(2) > 1e-9 * sv(0))) fail("circle fit: the {} points are collinear", points.size());
  const Eigen::Vector3d def = svd.solve(b);
  Vec2 centre(-def(0) / 2, -def(1) / 2);
  double radius = std::sqrt(std::max(centre.squaredNorm() - def(2), 0.0));
  centre += mean;
  // Gauss–Newton on r_i = |p_i − c| − R.
  for (int iteration = 0; iteration < 20; ++iteration) {
    Eigen::Matrix3d jtj = Eigen::Matrix3d::Zero();
    Eigen::Vector3d jtr = Eigen::Vector3d::Zero();
    for (const auto& p : points) {
      const Vec2 d = p - centre;
      const double dist = d.norm();
      if (dist < 1e-12) continue;
      const Eigen::Vector3d j(-d.x() / dist, -d.y() / dist, -1.0);
      const double r = dist - radius;
      jtj += j * j.transpose();
      jtr += j * r;
    }
    const Eigen::Vector3d step = jtj.ldlt().solve(-jtr);
    if (!step.allFinite()) break;
    centre += step.head<2>();
    radius += step(2);
    if (step.norm() < 1e-10) break;
  }
  if (!(radius > 0) || !centre.allFinite())
    fail("circle fit: no circle through the {} points", points.size());
  ImageCircle circle;
  circle.centre_px = centre;
  circle.radius_px = radius;
  circle.rms_px = rms_distance(points, centre, radius);
  circle.edge_points = points.size();
  return circle;
}

std::vector<ImageCircle> circles_from_mask(const cv::Mat& mask, const SphereDetectionOptions& options,
                                           const std::string& what) {
  options.check();
  if (mask.empty() || mask.type() != CV_8UC1) fail("{}: expected a CV_8UC1 mask", what);
  cv::Mat binary;
  cv::compare(mask, 0, binary, cv::CMP_GT);
  cv::Mat labels, stats, centroids;
  const int count = cv::connectedComponentsWithStats(binary, labels, stats, centroids, 4, CV_32S);
  const double min_area = kPi * options.min_radius_px * options.min_radius_px;
  std::vector<std::pair<int, int>> components;  // (area, label)
  for (int label = 1; label < count; ++label) {
    const int area = stats.at<int>(label, cv::CC_STAT_AREA);
    if (area >= min_area) components.emplace_back(area, label);
  }
  std::sort(components.rbegin(), components.rend());
  std::vector<ImageCircle> circles;
  for (const auto& [area, label] : components) {
    // The edge lies between an inside and an outside pixel centre: their midpoint.
    std::vector<Vec2> edge;
    for (int r = 0; r < labels.rows; ++r) {
      for (int c = 0; c < labels.cols; ++c) {
        const bool inside = labels.at<int>(r, c) == label;
        if (c + 1 < labels.cols && inside != (labels.at<int>(r, c + 1) == label))
          edge.emplace_back(c + 1.0, r + 0.5);
        if (r + 1 < labels.rows && inside != (labels.at<int>(r + 1, c) == label))
          edge.emplace_back(c + 0.5, r + 1.0);
      }
    }
    ImageCircle circle = fit_circle(edge);
    circle.source = "mask";
    if (circle.rms_px > options.max_rms_px) {
      fail(
          "{}: the mask region of {} pixels at ({:.0f}, {:.0f}) is not a circle (edge RMS {:.2f} px from the "
          "best circle, more than {} px)",
          what, area, circle.centre_px.x(), circle.centre_px.y(), circle.rms_px, options.max_rms_px);
    }
    circles.push_back(circle);
  }
  check_count(circles, options, what);
  return circles;
}

ImageCircle refine_circle(const cv::Mat& image, const ImageCircle& start, int profiles) {
  ImageCircle circle = start;
  for (int pass = 0; pass < 3; ++pass) {
    std::vector<Vec2> edge;
    const double r0 = circle.radius_px;
    const double inner = std::max(0.5 * r0, r0 - 8), outer = r0 + 8;
    constexpr double kStep = 0.25;
    for (int k = 0; k < profiles; ++k) {
      const double angle = 2 * kPi * k / profiles;
      const Vec2 dir(std::cos(angle), std::sin(angle));
      std::vector<double> radii, values;
      for (double r = inner; r <= outer; r += kStep) {
        const Vec2 p = circle.centre_px + r * dir;
        double value = 0;
        if (!sample(image, p.x(), p.y(), &value)) break;
        radii.push_back(r);
        values.push_back(value);
      }
      if (radii.empty() || radii.back() < outer - kStep) continue;  // the profile leaves the image
      // Inside and outside levels from the ends of the profile, the edge at half-way.
      const std::size_t quarter = values.size() / 4;
      const double in_level =
          median_of({values.begin(), values.begin() + static_cast<std::ptrdiff_t>(quarter)});
      const double out_level = median_of({values.end() - static_cast<std::ptrdiff_t>(quarter), values.end()});
      if (!(in_level > out_level)) continue;
      const double half = 0.5 * (in_level + out_level);
      // The crossing nearest the current radius.
      double best = -1, best_gap = 1e9;
      for (std::size_t i = 0; i + 1 < values.size(); ++i) {
        if ((values[i] - half) * (values[i + 1] - half) <= 0 && values[i] != values[i + 1]) {
          const double r = radii[i] + kStep * (values[i] - half) / (values[i] - values[i + 1]);
          if (std::abs(r - r0) < best_gap) {
            best_gap = std::abs(r - r0);
            best = r;
          }
        }
      }
      if (best > 0) edge.push_back(circle.centre_px + best * dir);
    }
    if (edge.size() < 16) return circle;  // cannot refine: keep the coarse circle
    // Drop outliers (a highlight or a dust speck on the edge) beyond 3 robust sigmas.
    const ImageCircle fitted = fit_circle(edge);
    std::vector<double> distances;
    for (const auto& p : edge)
      distances.push_back(std::abs((p - fitted.centre_px).norm() - fitted.radius_px));
    const double mad = median_of(distances);
    std::vector<Vec2> kept;
    for (std::size_t i = 0; i < edge.size(); ++i) {
      if (distances[i] <= std::max(3 * 1.4826 * mad, 0.05)) kept.push_back(edge[i]);
    }
    circle = fit_circle(kept.size() >= 16 ? kept : edge);
  }
  circle.source = "image";
  return circle;
}

std::vector<ImageCircle> detect_circles(const cv::Mat& image, const SphereDetectionOptions& options,
                                        const std::string& what) {
  options.check();
  if (image.empty() || image.type() != CV_32FC1) fail("{}: expected a CV_32FC1 image", what);
  // Otsu's threshold on the image scaled to 8 bits by a robust maximum.
  std::vector<float> values(image.begin<float>(), image.end<float>());
  const auto top = values.begin() + static_cast<std::ptrdiff_t>(values.size() * 999 / 1000);
  std::nth_element(values.begin(), top, values.end());
  const double high = *top;
  if (!(high > 0)) fail("{}: the image is black; no sphere to find", what);
  cv::Mat scaled;
  image.convertTo(scaled, CV_8UC1, 255.0 / high);
  cv::Mat binary;
  cv::threshold(scaled, binary, 0, 255, cv::THRESH_BINARY | cv::THRESH_OTSU);
  cv::morphologyEx(binary, binary, cv::MORPH_OPEN, cv::getStructuringElement(cv::MORPH_ELLIPSE, {5, 5}));
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(binary, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  std::vector<ImageCircle> circles;
  for (const auto& contour : contours) {
    if (contour.size() < 16) continue;
    std::vector<Vec2> points;
    for (const auto& p : contour) points.emplace_back(p.x + 0.5, p.y + 0.5);
    ImageCircle coarse;
    try {
      coarse = fit_circle(points);
    } catch (const InputError&) {
      continue;
    }
    const double area = cv::contourArea(contour);
    if (coarse.radius_px < options.min_radius_px) continue;
    // A circle: the outline hugs it and the area matches.
    if (coarse.rms_px > std::max(2.0, 0.03 * coarse.radius_px)) continue;
    if (std::abs(area / (kPi * coarse.radius_px * coarse.radius_px) - 1) > 0.15) continue;
    ImageCircle refined = refine_circle(image, coarse, options.profiles);
    if (refined.rms_px > options.max_rms_px) continue;
    circles.push_back(refined);
  }
  std::sort(circles.begin(), circles.end(),
            [](const ImageCircle& a, const ImageCircle& b) { return a.radius_px > b.radius_px; });
  check_count(circles, options, what);
  return circles;
}

}  // namespace lightstage::calibration
