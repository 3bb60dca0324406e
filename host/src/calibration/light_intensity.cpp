#include "lightstage/host/calibration/light_intensity.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/parallel.hpp"
#include "lightstage/host/io/temporary_rows.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

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

TargetSurface TargetSurface::sphere(const MirrorSphere& sphere, const CameraGeometry& camera,
                                    double margin_px) {
  const ImageCircle& circle = sphere.circle;
  const int r0 = std::max(0, static_cast<int>(circle.centre_px.y() - circle.radius_px) - 1);
  const int r1 = std::min(camera.height - 1, static_cast<int>(circle.centre_px.y() + circle.radius_px) + 1);
  const int c0 = std::max(0, static_cast<int>(circle.centre_px.x() - circle.radius_px) - 1);
  const int c1 = std::min(camera.width - 1, static_cast<int>(circle.centre_px.x() + circle.radius_px) + 1);
  TargetSurface surface(camera, r1 < r0 || c1 < c0 ? cv::Rect() : cv::Rect(c0, r0, c1 - c0 + 1, r1 - r0 + 1));
  surface.sphere_ = sphere;
  surface.margin_px_ = margin_px;
  return surface;
}

TargetSurface TargetSurface::plane(const cv::Mat& region, const CameraGeometry& camera, double z_mm) {
  TargetSurface surface(camera, cv::boundingRect(region));
  surface.region_ = region;
  surface.plane_z_mm_ = z_mm;
  return surface;
}

std::optional<TargetSurface::Point> TargetSurface::at(int column, int row) const {
  if (!bounds_.contains({column, row})) return std::nullopt;
  const Vec2 uv(column + 0.5, row + 0.5);
  if (sphere_) {
    if ((uv - sphere_->circle.centre_px).norm() > sphere_->circle.radius_px - margin_px_) return std::nullopt;
    const auto hit = reflect_at(*sphere_, camera_, uv);
    if (!hit) return std::nullopt;
    return Point{hit->point_mm, hit->normal};
  }
  if (region_.at<std::uint8_t>(row, column) == 0) return std::nullopt;
  Vec3 origin, dir;
  camera_.ray(uv, &origin, &dir);
  if (std::abs(dir.z()) < 1e-9) return std::nullopt;
  return Point{origin + (plane_z_mm_ - origin.z()) / dir.z() * dir, Vec3::UnitZ()};
}

LightGeometry LightGeometry::of(const LightCalibration& calibration) {
  LightGeometry geometry;
  geometry.object_centre_mm = calibration.object_position_mm;
  for (const auto& light : calibration.lights) {
    geometry.measured.push_back(light.measured);
    geometry.directions.push_back(light.direction);
    geometry.positions_mm.push_back(light.position_mm);
  }
  return geometry;
}

namespace {

// What one pass gathers of a light's pixels, given the flat field F of that
// pass: Σ v·s·F and Σ (s·F)² fit k; with Σ v² they give the misfit, with Σ v its level.
struct LightSums {
  double value_shading = 0, shading_squared = 0, value_squared = 0, value = 0;
  int used = 0;

  void add(const LightSums& other) {
    value_shading += other.value_shading;
    shading_squared += other.shading_squared;
    value_squared += other.value_squared;
    value += other.value;
    used += other.used;
  }
};

// One row's share of a pass: its lights' sums, and the flat field it found.
struct RowSums {
  std::vector<LightSums> lights;
  double flat = 0;
  std::size_t flat_pixels = 0;
  std::size_t target_pixels = 0;
};

// The passes of the fit over the target's rows, band by band.
class IntensityFit {
 public:
  // `passes`: how many times the target's rows are read (a band decoded in the first is kept on disk
  // for the others).
  IntensityFit(const CalibrationImages& index, const TargetSurface& surface, const LightGeometry& lights,
               const IntensityOptions& options, int threads, std::size_t band_bytes, int passes)
      : index_(index),
        surface_(surface),
        lights_(lights),
        options_(options),
        threads_(threads),
        passes_(passes),
        frames_(index, threads) {
    const cv::Rect& bounds = surface.bounds();
    const auto n = index.size();
    const auto width = static_cast<std::size_t>(bounds.width);
    // Per row of a band: each image's grey and saturation flag over the target's columns and each light's
    // sums; per thread, a row decoded whole (at most float RGB) and its double copy as it is made grey.
    const std::size_t row_bytes = n * (width * (4 + 1) + sizeof(LightSums)) +
                                  static_cast<std::size_t>(resolve_threads(threads)) *
                                      (static_cast<std::size_t>(index.width()) * 12 + width * 24);
    band_rows_ = static_cast<int>(
        std::clamp<std::size_t>(band_bytes / row_bytes, 1, static_cast<std::size_t>(bounds.height)));
  }

  // Pass over every row of the target: each pixel's flat field fitted to `k`
  // (written to `flat`), or F = 1 with no `k`; returns each light's sums with that F.
  std::vector<LightSums> pass(const std::vector<double>* k, cv::Mat& flat, double* flat_sum,
                              std::size_t* flat_pixels, std::size_t* target_pixels) {
    const cv::Rect& bounds = surface_.bounds();
    std::vector<LightSums> total(index_.size());
    *flat_sum = 0;
    *flat_pixels = *target_pixels = 0;
    for (int y0 = bounds.y; y0 < bounds.br().y; y0 += band_rows_) {
      const int rows = std::min(band_rows_, bounds.br().y - y0);
      load_band(y0, rows);
      std::vector<RowSums> sums(static_cast<std::size_t>(rows));
      parallel_for(rows, threads_, [&](int r) { sums[static_cast<std::size_t>(r)] = row(y0, r, k, flat); });
      for (const RowSums& row : sums) {  // in row order: the same sums whatever the threads
        for (std::size_t j = 0; j < total.size(); ++j) total[j].add(row.lights[j]);
        *flat_sum += row.flat;
        *flat_pixels += row.flat_pixels;
        *target_pixels += row.target_pixels;
      }
    }
    return total;
  }

 private:
  // Each image's grey values of rows [y0, y0 + rows) of the target, NaN where saturated. The target
  // in one band is decoded once and kept; in several, each band is decoded once and kept on disk
  // (io::TemporaryRows) for the passes after the first.
  void load_band(int y0, int rows) {
    const cv::Rect& bounds = surface_.bounds();
    if (rows == bounds.height && !grey_.empty()) return;
    const std::size_t n = index_.size();
    if (!spills_.empty() && spills_.front()->rows() >= y0 - bounds.y + rows) {
      parallel_for(static_cast<int>(n), threads_, [&](int i) {
        spills_[static_cast<std::size_t>(i)]->read(y0 - bounds.y, rows, grey_[static_cast<std::size_t>(i)]);
      });
      return;
    }
    std::vector<cv::Mat> saturated;
    frames_.read(y0, rows, cv::Range(bounds.x, bounds.br().x), grey_, saturated);
    if (rows < bounds.height && passes_ > 1 && spills_.empty())
      for (std::size_t i = 0; i < n; ++i)
        spills_.push_back(std::make_unique<io::TemporaryRows>((index_.folder / index_.filenames[i]).string(),
                                                              bounds.width, CV_32FC1, bounds.height));
    parallel_for(static_cast<int>(n), threads_, [&](int i) {
      const auto image = static_cast<std::size_t>(i);
      grey_[image].setTo(std::numeric_limits<float>::quiet_NaN(), saturated[image]);
      if (!spills_.empty()) spills_[image]->append(grey_[image]);
    });
  }

  RowSums row(int y0, int r, const std::vector<double>* k, cv::Mat& flat) const {
    const std::size_t n = index_.size();
    const cv::Rect& bounds = surface_.bounds();
    const int y = y0 + r;
    RowSums sums;
    sums.lights.resize(n);
    std::vector<double> shading(n), value(n);
    for (int c = 0; c < bounds.width; ++c) {
      const int x = bounds.x + c;
      const auto point = surface_.at(x, y);
      if (!point) continue;
      ++sums.target_pixels;
      for (std::size_t j = 0; j < n; ++j) {
        shading[j] = 0;
        if (!lights_.measured[j]) continue;
        const float v = grey_[j].at<float>(r, c);
        if (!(v > 0) || v > options_.max_value) continue;  // NaN: saturated
        Vec3 l = lights_.directions[j];
        double falloff = 1;
        if (lights_.positions_mm[j]) {
          const Vec3 to_led = *lights_.positions_mm[j] - point->point_mm;
          l = to_led.normalized();
          falloff =
              (*lights_.positions_mm[j] - lights_.object_centre_mm).squaredNorm() / to_led.squaredNorm();
        }
        const double cosine = point->normal.dot(l);
        if (cosine < options_.min_cosine) continue;
        shading[j] = static_cast<float>(cosine * falloff);
        value[j] = v;
      }
      double f = 1;
      if (k) {
        double num = 0, den = 0;
        for (std::size_t j = 0; j < n; ++j) {
          const double s = (*k)[j] * shading[j];
          num += value[j] * s;
          den += s * s;
        }
        // A pixel no light lights usably keeps F = 1 (marked −1 until the scale is known).
        if (!(den > 0)) {
          flat.at<float>(y, x) = -1;
          continue;
        }
        f = num / den;
        flat.at<float>(y, x) = static_cast<float>(f);
        sums.flat += f;
        ++sums.flat_pixels;
      }
      for (std::size_t j = 0; j < n; ++j) {
        if (shading[j] == 0) continue;
        const double s = f * shading[j];
        LightSums& light = sums.lights[j];
        light.value_shading += value[j] * s;
        light.shading_squared += s * s;
        light.value_squared += value[j] * value[j];
        light.value += value[j];
        ++light.used;
      }
    }
    return sums;
  }

  const CalibrationImages& index_;
  const TargetSurface& surface_;
  const LightGeometry& lights_;
  const IntensityOptions& options_;
  int threads_;
  int passes_;
  CalibrationRows frames_;
  int band_rows_ = 1;
  std::vector<cv::Mat> grey_;
  std::vector<std::unique_ptr<io::TemporaryRows>> spills_;  // per image: its target rows, when in bands
};

}  // namespace

IntensityResult fit_intensities(const CalibrationImages& index, const TargetSurface& surface,
                                const LightGeometry& lights, bool with_flat_field,
                                const IntensityOptions& options, int threads, std::size_t band_bytes) {
  options.check();
  const std::size_t n = index.size();
  if (lights.directions.size() != n || lights.positions_mm.size() != n || lights.measured.size() != n)
    fail("intensity fit: {} images but {} lights", n, lights.directions.size());
  if (surface.bounds().empty()) fail("{}: the intensity target covers no pixel", index.folder.string());
  const int rounds = with_flat_field ? options.iterations : 0;
  IntensityFit fit(index, surface, lights, options, threads, band_bytes, 1 + rounds);
  cv::Mat flat(index.image_size, CV_32FC1, cv::Scalar::all(0));
  double flat_sum = 0;
  std::size_t flat_pixels = 0, target_pixels = 0;
  // Pass 0 fits k with F = 1; each round after it fits F to k and k to that F (its scale, the mean of F,
  // taken out afterwards: k·F is what the images see).
  std::vector<LightSums> sums = fit.pass(nullptr, flat, &flat_sum, &flat_pixels, &target_pixels);
  if (target_pixels == 0) fail("{}: the intensity target covers no pixel", index.folder.string());
  IntensityResult result;
  result.relative.assign(n, 1.0);
  result.residual.assign(n, 0.0);
  result.pixels_used.assign(n, 0);
  result.target_pixels = target_pixels;
  for (std::size_t j = 0; j < n; ++j) {
    if (!lights.measured[j]) continue;
    if (sums[j].used < 16)
      fail("{}: image {} lights only {} usable pixel(s) of the target (at least 16 needed)",
           index.folder.string(), index.filenames[j], sums[j].used);
    result.relative[j] = sums[j].value_shading / sums[j].shading_squared;
    result.pixels_used[j] = sums[j].used;
  }
  double scale = 1;  // the mean of the last pass's F
  for (int round = 0; round < rounds; ++round) {
    const std::vector<double> k = result.relative;
    sums = fit.pass(&k, flat, &flat_sum, &flat_pixels, &target_pixels);
    scale = flat_pixels > 0 ? flat_sum / static_cast<double>(flat_pixels) : 1.0;
    // The misfit is that of the k this pass was given with its F; the last round's k is not used.
    if (round + 1 == rounds) break;
    for (std::size_t j = 0; j < n; ++j)
      if (lights.measured[j]) result.relative[j] = scale * sums[j].value_shading / sums[j].shading_squared;
  }
  // Residuals, with the F each sum was made with (F / scale is the flat field of mean 1), then
  // intensities scaled to mean 1.
  double sum = 0;
  int count = 0;
  for (std::size_t j = 0; j < n; ++j) {
    if (!lights.measured[j]) continue;
    const double k = result.relative[j] / scale;
    const LightSums& light = sums[j];
    const double squared =
        std::max(light.value_squared - 2 * k * light.value_shading + k * k * light.shading_squared, 0.0);
    result.residual[j] = std::sqrt(squared / light.used) / (light.value / light.used);
    sum += result.relative[j];
    ++count;
  }
  if (count > 0) {
    for (std::size_t j = 0; j < n; ++j) {
      if (lights.measured[j]) result.relative[j] /= sum / count;
    }
  }
  if (with_flat_field) {
    flat.forEach<float>([scale](float& f, const int*) {
      f = f > 0 ? static_cast<float>(f / scale) : f < 0 ? 1.f : 0.f;
    });
    result.flat_field = flat;
  }
  return result;
}

}  // namespace lightstage::calibration
