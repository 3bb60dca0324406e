#pragma once
// Natural lighting for the shape-prior experiments (dissertation Chapter 4):
// each image is lit by something other than the dome's LEDs — a few area
// lights (disks on the sky, e.g. windows and lamps) plus ambient light, or a
// whole environment given by spherical-harmonic coefficients — different per
// image. Shading is Lambertian with attached shadows,
//     shading(x) = albedo(x) · E(n(x)),  E(n) = (1/π) ∫ L(ω) max(n·ω, 0) dω
// (so a unit-radiance sky over the whole sphere gives E = 1, the sim's
// convention of material.hpp). Cast shadows are not rendered: the method
// does not model them either (dissertation §4.6, limitations).

#include "lightstage/common/geometry.hpp"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <cstdint>
#include <vector>

namespace lightstage::sim {

// A disk of constant radiance on the sky.
struct AreaLight {
  Vec3 direction = Vec3::UnitZ();  // centre, unit, object → light
  double half_angle_rad = 0.1;     // angular radius
  double radiance = 1.0;
};

struct NaturalLighting {
  std::vector<AreaLight> areas;
  double sky = 0;      // radiance of a uniform sky over the upper hemisphere (z > 0 side of the camera)
  double ambient = 0;  // radiance from every direction
  // Real spherical-harmonic coefficients of an environment's radiance, bands
  // 0..2 (1, 4 or 9 values in the order Y00, Y1-1, Y10, Y11, Y2-2, ...); the
  // irradiance is their exact convolution with the clamped cosine.
  std::vector<double> sh;

  // E(n) for a unit normal; area lights are integrated numerically over
  // `samples` directions each.
  double irradiance(const Vec3& n, int samples = 96) const;
  nlohmann::json describe() const;
};

enum class NaturalLightingKind { kAreaLights, kSphericalHarmonics };

struct NaturalLightingOptions {
  NaturalLightingKind kind = NaturalLightingKind::kAreaLights;
  int images = 40;
  int min_area_lights = 1, max_area_lights = 3;
  double min_half_angle_deg = 3, max_half_angle_deg = 20;
  double min_elevation_deg = 15;                 // area lights stay this far above the image plane
  double min_ambient = 0.02, max_ambient = 0.2;  // relative to the brightest area light's irradiance
  double sh_variation = 0.6;  // spread of the non-constant SH coefficients (relative to Y00)
  std::uint64_t seed = 1;

  void check() const;  // throws InputError naming the field
};

// One random lighting per image, reproducible from the seed.
std::vector<NaturalLighting> random_natural_lighting(const NaturalLightingOptions& options);

// Shading image (CV_64FC1) of unit `normals` (CV_32FC3 x y z) with `albedo`
// (CV_32FC1) inside `mask` (CV_8UC1) under `lighting`; 0 outside the mask.
cv::Mat render_natural(const cv::Mat& normals, const cv::Mat& albedo, const cv::Mat& mask,
                       const NaturalLighting& lighting, int threads = 0);

// The real spherical harmonics of bands 0..2 at a unit direction (9 values).
std::vector<double> sh_basis9(const Vec3& n);

}  // namespace lightstage::sim
