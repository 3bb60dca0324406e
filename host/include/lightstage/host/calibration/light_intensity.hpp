#pragma once
// Relative light intensities from a Lambertian target under the calibrated
// lights. Model, per light j and target pixel x:
//     I_j(x) = k_j · F(x) · max(n(x)·l_j(x), 0) · E_j(x)
// with l_j(x) and the falloff E_j(x) = |p_j − o|² / |p_j − x|² from the LED
// position p_j when known (else the distant direction and E = 1). A matte
// sphere has uniform albedo: F = 1 and each k_j is a linear least-squares
// fit. A flat white target also gives the flat field F (albedo, vignetting):
// k and F are fitted in turn. Intensities are scaled to mean 1, F to mean 1.

#include "lightstage/host/calibration/calibration_images.hpp"
#include "lightstage/host/calibration/camera_geometry.hpp"
#include "lightstage/host/calibration/light_calibration.hpp"
#include "lightstage/host/calibration/mirror_sphere.hpp"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace lightstage::calibration {

enum class IntensityTarget { kMatteSphere, kFlatTarget };
IntensityTarget parse_intensity_target(const std::string& text);  // "matte-sphere" | "flat-target"
const char* intensity_target_name(IntensityTarget target);

struct IntensityOptions {
  double min_cosine = 0.2;  // pixels lit more obliquely than this are not used
  double max_value = 0.95;  // nor pixels this bright (near saturation)
  int iterations = 10;      // flat target: rounds of fitting k and F in turn

  void check() const;  // throws InputError naming the field
};

// The target's visible surface: which pixels it covers, and the 3-D point and
// normal of each, worked out when asked, so that a target as large as the
// image is never held pixel by pixel.
class TargetSurface {
 public:
  struct Point {
    Vec3 point_mm;
    Vec3 normal;
  };
  // A matte sphere's pixels (those inside its outline, less a rim of `margin_px`).
  static TargetSurface sphere(const MirrorSphere& sphere, const CameraGeometry& camera, double margin_px = 2);
  // A flat target facing the camera at height z_mm, over the pixels of `region` (CV_8UC1).
  static TargetSurface plane(const cv::Mat& region, const CameraGeometry& camera, double z_mm);

  // Every pixel of the target lies inside (empty when it covers none).
  const cv::Rect& bounds() const { return bounds_; }
  // The surface seen through pixel (column, row) of the image; nullopt off the target.
  std::optional<Point> at(int column, int row) const;

 private:
  TargetSurface(const CameraGeometry& camera, cv::Rect bounds) : camera_(camera), bounds_(bounds) {}

  CameraGeometry camera_;
  cv::Rect bounds_;
  std::optional<MirrorSphere> sphere_;
  double margin_px_ = 0;
  cv::Mat region_;  // the plane's pixels
  double plane_z_mm_ = 0;
};

// What the fit needs to know of each light (one per image).
struct LightGeometry {
  std::vector<bool> measured;    // false: skipped, intensity stays 1
  std::vector<Vec3> directions;  // from the object centre
  std::vector<std::optional<Vec3>> positions_mm;
  Vec3 object_centre_mm = Vec3::Zero();

  // The lights a calibration measured: directions, and LED positions where it has them.
  static LightGeometry of(const LightCalibration& calibration);
};

struct IntensityResult {
  std::vector<double> relative;   // per light; mean 1 over the lights fitted
  std::vector<double> residual;   // per light, RMS misfit / mean value
  std::vector<int> pixels_used;   // per light
  cv::Mat flat_field;             // flat target: CV_32FC1, mean 1 over the target; else empty
  std::size_t target_pixels = 0;  // the target's pixels in the images
};

// Fits the model above to the images of `index`, read a band of rows at a
// time (CalibrationRows). The fit decodes the rows of the target's bounding
// box once: they are kept in memory when they fit in `band_bytes`, else, for
// the flat target's rounds after the first, band by band on disk
// (io::TemporaryRows, 4 bytes per image and pixel of the box). Throws
// InputError naming the image when a measured light lights fewer than 16
// usable pixels, and naming the folder when the target covers no pixel.
IntensityResult fit_intensities(const CalibrationImages& index, const TargetSurface& surface,
                                const LightGeometry& lights, bool with_flat_field,
                                const IntensityOptions& options, int threads = 0,
                                std::size_t band_bytes = std::size_t{512} << 20);

}  // namespace lightstage::calibration
