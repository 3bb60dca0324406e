#pragma once
// A material: a spatially varying diffuse albedo texture times a diffuse
// lobe, plus a weighted specular lobe (brdf.hpp). The rendered value at unit
// irradiance is
//     shading = (kd · albedo(x, y) · diffuse(n,l,v) + ks · specular(n,l,v)) · max(n·l, 0)
// A material with a colour (ColourTexture) is dichromatic: in channel c
//     shading_c = (kd · albedo(x, y) · tint_c(x, y) · diffuse(n,l,v) + ks · specular(n,l,v)) · max(n·l, 0)
// the diffuse part takes the colour, the specular lobe (and a mirror) stays
// white, as on dielectrics. The tint's BT.601 grey is 1, so the grey of a
// colour rendering is the rendering without the colour.
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
#include <optional>
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

// BT.601 luma weights of linear R, G, B: the grey the host makes of a colour frame.
inline constexpr double kGreyRed = 0.2989, kGreyGreen = 0.5870, kGreyBlue = 0.1140;
inline double bt601_grey(const Vec3& rgb) {
  return kGreyRed * rgb.x() + kGreyGreen * rgb.y() + kGreyBlue * rgb.z();
}

// Colour of the diffuse albedo over the object plane (x, y in millimetres,
// object frame). eval returns the tint (r, g, b): the colour scaled so that
// its BT.601 grey is 1 — only the hue and saturation of the colours given
// here matter, the brightness is the albedo's.
struct ColourTexture {
  enum class Kind {
    kConstant,  // colour `a` everywhere
    kChecker,   // squares of side period_mm, alternately `a` and `b`
    kPatches,   // cells of side period_mm, each a random hue at `saturation` (HSV, value 1)
  };
  Kind kind = Kind::kConstant;
  Vec3 a = Vec3::Ones();  // r, g, b >= 0, not black
  Vec3 b = Vec3::Ones();
  double period_mm = 10.0;
  double saturation = 0.5;  // patches: 0 = grey .. 1 = fully saturated hues
  std::uint64_t seed = 1;   // patches

  Vec3 eval(double x_mm, double y_mm) const;  // the tint (r, g, b), BT.601 grey 1
  void check() const;                         // throws InputError naming the field
  nlohmann::json describe() const;
};

// `rgb` scaled to BT.601 grey 1; throws InputError (naming `what`) for a
// negative, non-finite or black colour.
Vec3 normalised_tint(const Vec3& rgb, const std::string& what);

struct Material {
  AlbedoTexture albedo;
  std::optional<ColourTexture> colour;                                // unset = grey (single-channel frames)
  std::shared_ptr<const Brdf> diffuse = std::make_shared<Lambert>();  // null = none
  double kd = 1.0;
  std::shared_ptr<const Brdf> specular;  // null = none
  double ks = 0.0;
  std::string preset = "lambert";  // the string it was parsed from

  // Grey shading at unit irradiance (the colour's BT.601 grey), including
  // max(n·l, 0); mirrors contribute 0 here.
  double shading(double x_mm, double y_mm, const Vec3& n, const Vec3& l, const Vec3& v) const;
  bool is_mirror() const { return specular && specular->is_mirror(); }
  // Mirror reflectance (ks of a chrome material).
  double mirror_reflectance() const { return is_mirror() ? ks : 0.0; }
  nlohmann::json describe() const;
};

// Parses a material preset string; `albedo` is the texture to keep unless the
// string sets a constant `albedo=`. The result has no colour (the scene's
// `colour` key sets it). Throws InputError naming the key.
Material parse_material(const std::string& preset, const AlbedoTexture& albedo = {});

// The preset names parse_material knows, for --help.
std::vector<std::string> material_presets();

}  // namespace lightstage::sim
