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
#include "lightstage/host/calibration/mirror_sphere.hpp"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

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

// The target's visible surface: pixels with their 3-D point and normal.
struct TargetSurface {
  std::vector<cv::Point> pixels;
  std::vector<Vec3> points_mm;
  std::vector<Vec3> normals;
};

// A matte sphere's pixels (those inside its outline, less a rim of `margin_px`).
TargetSurface sphere_surface(const MirrorSphere& sphere, const CameraGeometry& camera, double margin_px = 2);
// A flat target facing the camera at height z_mm, over the pixels of `region` (CV_8UC1).
TargetSurface plane_surface(const cv::Mat& region, const CameraGeometry& camera, double z_mm);

// What the fit needs to know of each light (one per image).
struct LightGeometry {
  std::vector<bool> measured;    // false: skipped, intensity stays 1
  std::vector<Vec3> directions;  // from the object centre
  std::vector<std::optional<Vec3>> positions_mm;
  Vec3 object_centre_mm = Vec3::Zero();
};

struct IntensityResult {
  std::vector<double> relative;  // per light; mean 1 over the lights fitted
  std::vector<double> residual;  // per light, RMS misfit / mean value
  std::vector<int> pixels_used;  // per light
  cv::Mat flat_field;            // flat target: CV_32FC1, mean 1 over the target; else empty
};

// Fits the model above. Throws InputError naming the image when a measured
// light lights fewer than 16 usable pixels.
IntensityResult fit_intensities(const CalibrationImages& images, const TargetSurface& surface,
                                const LightGeometry& lights, bool with_flat_field,
                                const IntensityOptions& options);

}  // namespace lightstage::calibration
