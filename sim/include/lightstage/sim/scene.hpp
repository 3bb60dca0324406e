#pragma once
// A scene: the object (shape + material), how the camera sees it and how the
// LEDs look in a mirror. Scenes come from YAML files or named presets
// (scene_file.hpp); the camera starts from the rig's CameraDefaults.

#include "lightstage/common/rig.hpp"
#include "lightstage/sim/material.hpp"
#include "lightstage/sim/shape.hpp"

#include <nlohmann/json.hpp>

#include <memory>
#include <optional>
#include <string>

namespace lightstage::sim {

// Camera overrides a scene may carry; unset fields keep the rig's.
struct CameraOverrides {
  std::optional<CameraModel> model;
  std::optional<int> width, height;
  std::optional<double> pixel_pitch_mm;
  std::optional<double> focal_px;
  std::optional<Vec3> position_mm;
};

struct Scene {
  std::string name;                    // preset name or file path
  std::shared_ptr<const Shape> shape;  // object frame: origin at the rig's object position
  Material material;
  CameraOverrides camera;
  double led_radius_mm = 2.5;      // LEDs as seen in a mirror: disks of this radius
  double led_radiance = 1.0;       // their radiance, in shading units (a mirror of reflectance 1 shows this)
  double highlight_blur_px = 0.7;  // lens PSF (Gaussian sigma, pixels) applied to mirror highlights; 0 = none
  // A mirror also reflects the dome's interior, lit by the LEDs that are on: a
  // uniform radiance of this much per unit LED intensity, anti-aliased at the
  // silhouette, so a chrome sphere's outline can be found in the images. 0 = none.
  double environment_radiance = 0.0;
  bool cast_shadows = true;  // march shadow rays (height fields)

  nlohmann::json describe() const;
};

// The camera that renders: pixel (col, row) has its centre at (col+0.5, row+0.5).
struct Camera {
  CameraModel model = CameraModel::kOrthographic;
  int width = 512;
  int height = 512;
  double pixel_pitch_mm = 0.2;          // orthographic
  double focal_px = 0;                  // pinhole
  Vec3 position_mm = Vec3(0, 0, 1000);  // dome frame; orthographic: the optical axis passes through it

  // Ray through image point (u, v) in pixels (u right, v down), dome frame.
  void ray(double u, double v, Vec3* origin, Vec3* dir) const;
  nlohmann::json describe() const;
};

// The rig's camera with the scene's overrides, then `width`/`height` (when
// given) applied keeping the field of view: the pixel pitch (orthographic) or
// focal length (pinhole) scales with the size, square pixels, fitting both.
Camera make_camera(const CameraDefaults& rig_camera, const CameraOverrides& scene, std::optional<int> width,
                   std::optional<int> height);

}  // namespace lightstage::sim
