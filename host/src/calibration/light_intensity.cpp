#include "lightstage/host/calibration/light_intensity.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/parallel.hpp"

#include <cmath>

namespace lightstage::calibration {

IntensityTarget parse_intensity_target(const std::string& text) {
  if (text == "matte-sphere") return IntensityTarget::kMatteSphere;
  if (text == "flat-target") return IntensityTarget::kFlatTarget;
  fail("intensity target must be 'matte-sphere' or 'flat-target', got '{}'", text);
}

const char* intensity_target_name(IntensityTarget target) {
  return target == IntensityTarget::kMatteSphere ? "matte-sphere" : "flat-target";
}

void IntensityOptions::check() const {
  if (!(min_cosine >= 0 && min_cosine < 1))
    fail("IntensityOptions.min_cosine: must be in [0, 1), got {}", min_cosine);
  if (!(max_value > 0)) fail("IntensityOptions.max_value: must be positive, got {}", max_value);
  if (iterations < 1) fail("IntensityOptions.iterations: must be at least 1, got {}", iterations);
}

TargetSurface sphere_surface(const MirrorSphere& sphere, const CameraGeometry& camera, double margin_px) {
  TargetSurface surface;
  const ImageCircle& circle = sphere.circle;
  const int r0 = std::max(0, static_cast<int>(circle.centre_px.y() - circle.radius_px) - 1);
  const int r1 = std::min(camera.height - 1, static_cast<int>(circle.centre_px.y() + circle.radius_px) + 1);
  const int c0 = std::max(0, static_cast<int>(circle.centre_px.x() - circle.radius_px) - 1);
  const int c1 = std::min(camera.width - 1, static_cast<int>(circle.centre_px.x() + circle.radius_px) + 1);
  for (int r = r0; r <= r1; ++r) {
    for (int c = c0; c <= c1; ++c) {
      const Vec2 uv(c + 0.5, r + 0.5);
      if ((uv - circle.centre_px).norm() > circle.radius_px - margin_px) continue;
      const auto hit = reflect_at(sphere, camera, uv);
      if (!hit) continue;
      surface.pixels.emplace_back(c, r);
      surface.points_mm.push_back(hit->point_mm);
      surface.normals.push_back(hit->normal);
    }
  }
  return surface;
}

TargetSurface plane_surface(const cv::Mat& region, const CameraGeometry& camera, double z_mm) {
  TargetSurface surface;
  for (int r = 0; r < region.rows; ++r) {
    for (int c = 0; c < region.cols; ++c) {
      if (region.at<std::uint8_t>(r, c) == 0) continue;
      Vec3 origin, dir;
      camera.ray(Vec2(c + 0.5, r + 0.5), &origin, &dir);
      if (std::abs(dir.z()) < 1e-9) continue;
      const double t = (z_mm - origin.z()) / dir.z();
      surface.pixels.emplace_back(c, r);
      surface.points_mm.push_back(origin + t * dir);
      surface.normals.push_back(Vec3::UnitZ());
    }
  }
  return surface;
}

IntensityResult fit_intensities(const CalibrationImages& images, const TargetSurface& surface,
                                const LightGeometry& lights, bool with_flat_field,
                                const IntensityOptions& options) {
  options.check();
  const std::size_t n = images.size(), m = surface.pixels.size();
  if (lights.directions.size() != n || lights.positions_mm.size() != n || lights.measured.size() != n)
    fail("intensity fit: {} images but {} lights", n, lights.directions.size());
  if (m == 0) fail("{}: the intensity target covers no pixel", images.folder.string());
  // Shading at unit intensity and flat field, per light and pixel (0 = not used).
  std::vector<std::vector<float>> shading(n, std::vector<float>(m, 0.f));
  std::vector<std::vector<float>> value(n, std::vector<float>(m, 0.f));
  parallel_chunks(n, 0, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t j = begin; j < end; ++j) {
      if (!lights.measured[j]) continue;
      for (std::size_t i = 0; i < m; ++i) {
        const cv::Point& px = surface.pixels[i];
        const float v = images.grey[j].at<float>(px);
        if (images.saturated[j].at<std::uint8_t>(px) != 0 || !(v > 0) || v > options.max_value) continue;
        Vec3 l = lights.directions[j];
        double falloff = 1;
        if (lights.positions_mm[j]) {
          const Vec3 to_led = *lights.positions_mm[j] - surface.points_mm[i];
          l = to_led.normalized();
          falloff = (*lights.positions_mm[j] - lights.object_centre_mm).squaredNorm() / to_led.squaredNorm();
        }
        const double cosine = surface.normals[i].dot(l);
        if (cosine < options.min_cosine) continue;
        shading[j][i] = static_cast<float>(cosine * falloff);
        value[j][i] = v;
      }
    }
  });
  IntensityResult result;
  result.relative.assign(n, 1.0);
  result.residual.assign(n, 0.0);
  result.pixels_used.assign(n, 0);
  std::vector<double> flat(m, 1.0);
  const int rounds = with_flat_field ? options.iterations : 1;
  for (int round = 0; round < rounds; ++round) {
    for (std::size_t j = 0; j < n; ++j) {
      if (!lights.measured[j]) continue;
      double num = 0, den = 0;
      int used = 0;
      for (std::size_t i = 0; i < m; ++i) {
        if (shading[j][i] == 0) continue;
        const double s = flat[i] * shading[j][i];
        num += value[j][i] * s;
        den += s * s;
        ++used;
      }
      if (used < 16) {
        fail("{}: image {} lights only {} usable pixel(s) of the target (at least 16 needed)",
             images.folder.string(), images.filenames[j], used);
      }
      result.relative[j] = num / den;
      result.pixels_used[j] = used;
    }
    if (!with_flat_field) break;
    double total = 0;
    int counted = 0;
    for (std::size_t i = 0; i < m; ++i) {
      double num = 0, den = 0;
      for (std::size_t j = 0; j < n; ++j) {
        if (shading[j][i] == 0) continue;
        const double s = result.relative[j] * shading[j][i];
        num += value[j][i] * s;
        den += s * s;
      }
      if (den > 0) {
        flat[i] = num / den;
        total += flat[i];
        ++counted;
      }
    }
    // Fix the scale between k and F: F has mean 1.
    const double mean = counted > 0 ? total / counted : 1.0;
    for (double& f : flat) f /= mean;
  }
  // Residuals, then scale intensities to mean 1.
  double sum = 0;
  int count = 0;
  for (std::size_t j = 0; j < n; ++j) {
    if (!lights.measured[j]) continue;
    double squared = 0, level = 0;
    for (std::size_t i = 0; i < m; ++i) {
      if (shading[j][i] == 0) continue;
      const double r = value[j][i] - result.relative[j] * flat[i] * shading[j][i];
      squared += r * r;
      level += value[j][i];
    }
    const int used = result.pixels_used[j];
    result.residual[j] = std::sqrt(squared / used) / (level / used);
    sum += result.relative[j];
    ++count;
  }
  if (count > 0) {
    for (std::size_t j = 0; j < n; ++j) {
      if (lights.measured[j]) result.relative[j] /= sum / count;
    }
  }
  if (with_flat_field) {
    result.flat_field = cv::Mat(images.height(), images.width(), CV_32FC1, cv::Scalar::all(0));
    for (std::size_t i = 0; i < m; ++i)
      result.flat_field.at<float>(surface.pixels[i]) = static_cast<float>(flat[i]);
  }
  return result;
}

}  // namespace lightstage::calibration
