#include "lightstage/host/calibration/calibration_plot.hpp"

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace lightstage::calibration {
namespace {

constexpr int kShift = 4;  // sub-pixel drawing: coordinates × 16
const cv::Scalar kNominal(150, 150, 150), kCalibrated(40, 90, 230), kGrid(215, 215, 215), kText(60, 60, 60);

cv::Point fixed(const Vec2& p) {
  return {static_cast<int>(std::lround(p.x() * (1 << kShift))),
          static_cast<int>(std::lround(p.y() * (1 << kShift)))};
}

// Polar position of a direction: radius ∝ 90° − elevation, azimuth counter-clockwise from +x (image right).
Vec2 polar(const Vec3& d, const Vec2& centre, double radius) {
  const Vec3 u = d.normalized();
  const double elevation = std::asin(std::clamp(u.z(), -1.0, 1.0));
  const double r = radius * (1 - elevation / (kPi / 2));
  const double azimuth = std::atan2(u.y(), u.x());
  return centre + r * Vec2(std::cos(azimuth), -std::sin(azimuth));
}

}  // namespace

cv::Mat hemisphere_plot(const LightCalibration& calibration, int size) {
  cv::Mat image(size, size, CV_8UC3, cv::Scalar(255, 255, 255));
  const Vec2 centre(size / 2.0, size / 2.0 + 20);
  const double radius = size * 0.42;
  for (int elevation = 0; elevation < 90; elevation += 15) {
    cv::circle(image, fixed(centre), static_cast<int>(radius * (1 - elevation / 90.0) * (1 << kShift)), kGrid,
               1, cv::LINE_AA, kShift);
    cv::putText(image, fmt::format("{}", elevation),
                cv::Point(static_cast<int>(centre.x() + radius * (1 - elevation / 90.0)) + 3,
                          static_cast<int>(centre.y()) - 3),
                cv::FONT_HERSHEY_SIMPLEX, 0.35, kText, 1, cv::LINE_AA);
  }
  for (int azimuth = 0; azimuth < 360; azimuth += 30) {
    const double a = azimuth * kPi / 180;
    cv::line(image, fixed(centre), fixed(centre + radius * Vec2(std::cos(a), -std::sin(a))), kGrid, 1,
             cv::LINE_AA, kShift);
  }
  const Vec3 object = calibration.object_position_mm;
  double worst = 0, sum = 0;
  int compared = 0;
  for (const auto& light : calibration.lights) {
    if (!light.measured) continue;
    const Vec2 at = polar(light.direction, centre, radius);
    if (light.nominal_position_mm) {
      const Vec3 nominal = *light.nominal_position_mm - object;
      const Vec2 nominal_at = polar(nominal, centre, radius);
      cv::circle(image, fixed(nominal_at), 7 << kShift, kNominal, 1, cv::LINE_AA, kShift);
      cv::line(image, fixed(nominal_at), fixed(at), kNominal, 1, cv::LINE_AA, kShift);
      const double error = angle_between_deg(nominal, light.direction);
      worst = std::max(worst, error);
      sum += error;
      ++compared;
    }
    cv::circle(image, fixed(at), 3 << kShift, kCalibrated, cv::FILLED, cv::LINE_AA, kShift);
    if (light.led_id >= 0) {
      cv::putText(image, fmt::format("{}", light.led_id),
                  cv::Point(static_cast<int>(at.x()) + 5, static_cast<int>(at.y()) - 5),
                  cv::FONT_HERSHEY_SIMPLEX, 0.3, kText, 1, cv::LINE_AA);
    }
  }
  std::string title =
      fmt::format("{} lights, directions: {}", calibration.lights.size(), calibration.direction_method);
  cv::putText(image, title, {12, 22}, cv::FONT_HERSHEY_SIMPLEX, 0.55, kText, 1, cv::LINE_AA);
  std::string legend = "filled: calibrated";
  if (compared > 0)
    legend += fmt::format("   hollow: nominal (rig)   calibrated vs nominal: mean {:.3f} deg, max {:.3f} deg",
                          sum / compared, worst);
  cv::putText(image, legend, {12, 44}, cv::FONT_HERSHEY_SIMPLEX, 0.45, kText, 1, cv::LINE_AA);
  return image;
}

cv::Mat highlight_overlay(const cv::Mat& view, const LightCalibration& calibration,
                          const std::filesystem::path& stack) {
  // Tone map: square root of the value over a high percentile, so the dim sphere and bright highlights both
  // show.
  std::vector<float> values(view.begin<float>(), view.end<float>());
  const auto top = values.begin() + static_cast<std::ptrdiff_t>(values.size() * 998 / 1000);
  std::nth_element(values.begin(), top, values.end());
  const double high = std::max(static_cast<double>(*top), 1e-6);
  cv::Mat scaled;
  cv::sqrt(cv::max(view, 0.0) / high, scaled);
  cv::Mat grey8;
  scaled.convertTo(grey8, CV_8UC1, 200.0);
  cv::Mat image;
  cv::cvtColor(grey8, image, cv::COLOR_GRAY2BGR);
  for (std::size_t s = 0; s < calibration.spheres.size(); ++s) {
    if (calibration.spheres[s].stack != stack) continue;
    const ImageCircle& circle = calibration.spheres[s].sphere.circle;
    cv::circle(image, fixed(circle.centre_px - Vec2(0.5, 0.5)),
               static_cast<int>(circle.radius_px * (1 << kShift)), cv::Scalar(255, 160, 0), 1, cv::LINE_AA,
               kShift);
    for (const auto& light : calibration.lights) {
      for (const auto& o : light.observations) {
        if (o.sphere != s || !o.highlight.usable()) continue;
        const Vec2 p = o.highlight.centre_px - Vec2(0.5, 0.5);  // drawing uses pixel-centre coordinates
        const cv::Scalar colour =
            o.highlight.status == HighlightStatus::kFound ? cv::Scalar(0, 200, 0) : cv::Scalar(0, 200, 255);
        cv::drawMarker(image,
                       cv::Point(static_cast<int>(std::lround(p.x())), static_cast<int>(std::lround(p.y()))),
                       colour, cv::MARKER_CROSS, 9, 1, cv::LINE_AA);
      }
    }
  }
  return image;
}

}  // namespace lightstage::calibration
