#pragma once
// A material: a spatially varying diffuse albedo texture times a diffuse
// lobe, plus a weighted specular lobe (brdf.hpp). The rendered value at unit
// irradiance is
//     shading = (kd · albedo(x, y) · diffuse(n,l,v) + ks · specular(n,l,v)) · max(n·l, 0)
// Materials come from preset strings: "lambert", "blinn-phong:shininess=50",
// "cook-torrance:roughness=0.3,ks=0.5", "ward:alpha=0.2",
// "oren-nayar:sigma=0.3", "two-lobe-ct:k1=0.5,k2=0.5",
// "two-lobe-fabric:k1=0.5,k2=0.5", "two-lobe-random:k1=0.5,k2=0.5", "chrome"
// (docs/scene-format.md lists every key).

#include "lightstage/common/geometry.hpp"
#include "lightstage/sim/brdf.hpp"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace lightstage::sim {

// Diffuse albedo over the object plane (x, y in millimetres, object frame).
struct AlbedoTexture {
  enum class Kind { kConstant, kChecker, kPatches, kNoise };
  Kind kind = Kind::kConstant;
  double a = 1.0;           // constant value; checker/patches/noise: lower value
  double b = 1.0;           // checker/patches/noise: upper value
  double period_mm = 10.0;  // checker square / patch cell / noise wavelength
  std::uint64_t seed = 1;   // patches and noise

  double eval(double x_mm, double y_mm) const;
  void check() const;  // throws InputError naming the field
  nlohmann::json describe() const;
};

struct Material {
  AlbedoTexture albedo;
  std::shared_ptr<const Brdf> diffuse = std::make_shared<Lambert>();  // null = none
  double kd = 1.0;
  std::shared_ptr<const Brdf> specular;  // null = none
  double ks = 0.0;
  std::string preset = "lambert";  // the string it was parsed from

  // Shading at unit irradiance, including max(n·l, 0); mirrors contribute 0 here.
  double shading(double x_mm, double y_mm, const Vec3& n, const Vec3& l, const Vec3& v) const;
  bool is_mirror() const { return specular && specular->is_mirror(); }
  // Mirror reflectance (ks of a chrome material).
  double mirror_reflectance() const { return is_mirror() ? ks : 0.0; }
  nlohmann::json describe() const;
};

// Parses a material preset string; `albedo` is the texture to keep unless the
// string sets a constant `albedo=`. Throws InputError naming the key.
Material parse_material(const std::string& preset, const AlbedoTexture& albedo = {});

// The preset names parse_material knows, for --help.
std::vector<std::string> material_presets();

}  // namespace lightstage::sim
