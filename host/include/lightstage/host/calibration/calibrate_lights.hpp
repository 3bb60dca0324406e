#pragma once
// `lightstage calibrate lights` as one library call: chrome-sphere stacks in,
// a LightCalibration out. Each stack holds the same lights in the same order
// (one image per light), with one or more mirror spheres; every sphere gives
// each light a mirror direction, and two or more sphere positions (several
// stacks, or several spheres in a stack) triangulate the LED positions. The
// directions reported are from the object centre: from triangulated
// positions, or — one sphere position — from where the reflected rays meet
// the dome (when its radius is known), else the mirror directions themselves.

#include "lightstage/host/calibration/calibration_images.hpp"
#include "lightstage/host/calibration/light_calibration.hpp"
#include "lightstage/host/calibration/light_intensity.hpp"

#include <filesystem>
#include <optional>
#include <vector>

namespace lightstage::calibration {

struct LightCalibrationOptions {
  // Chrome-sphere stacks: one per sphere position, same lights, same order.
  std::vector<std::filesystem::path> inputs;
  // Spheres in each stack (all found, left to right).
  int spheres_per_stack = 1;
  // Sphere outlines given by hand (image points and radius, pixels), used for
  // every stack instead of detection; empty = from mask.png, else detected.
  std::vector<ImageCircle> given_circles;
  // Orthographic camera: height (dome-frame z, mm) of the sphere centres —
  // one value for all stacks or one per stack; empty = the object position's.
  std::vector<double> sphere_z_mm;
  // Pinhole camera: the spheres' true radius (mm).
  double sphere_radius_mm = 0;
  // Optional rig file: camera, object position, dome radius, nominal LED positions.
  std::filesystem::path rig;
  // Dome radius for the one-sphere correction; unset = the rig's; 0 = none.
  std::optional<double> dome_radius_mm;
  // Camera override; unset = the stack's manifest, else the rig, else unknown scale.
  std::optional<CameraGeometry> camera;
  // Optional: a matte sphere or flat white target under the same lights, for intensities.
  std::filesystem::path intensity_input;
  IntensityTarget intensity_target = IntensityTarget::kMatteSphere;
  IntensityOptions intensity;
  SphereDetectionOptions detection;
  HighlightOptions highlight;
  // Write a calibration even when some lights have no usable highlight (they are marked unmeasured).
  bool allow_missing = false;
  int threads = 0;  // 0 = hardware concurrency

  void check() const;  // throws InputError naming the field
};

struct LightCalibrationRun {
  LightCalibration calibration;
  std::vector<cv::Mat> sphere_views;  // per input stack: its maximum image (CV_32FC1), for pictures
  cv::Mat flat_field;                 // CV_32FC1 from a flat target, else empty
  double seconds = 0;
};

// The spheres of one stack as the calibration finds them: the given circles,
// else its mask.png's, else detected on `median`, the median of its images
// (calibration_views); left to right. Throws InputError naming the stack when
// they cannot be found.
std::vector<ImageCircle> find_sphere_circles(const CalibrationImages& images, const cv::Mat& median,
                                             const LightCalibrationOptions& options);

// Throws InputError naming the stack and images when a sphere cannot be
// found, when images differ between stacks, or (unless allow_missing) when
// a light has no usable highlight on any sphere — listing every such image and why.
LightCalibrationRun calibrate_lights(const LightCalibrationOptions& options);

}  // namespace lightstage::calibration
