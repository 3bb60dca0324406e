#include "lightstage/sim/material.hpp"

#include "lightstage/common/error.hpp"

#include <algorithm>
#include <cmath>
#include <set>

namespace lightstage::sim {
namespace {

// Floor to a cell index without UB for huge or non-finite coordinates.
std::int64_t cell(double x) {
  const double f = std::floor(x);
  if (!(f > -1e15 && f < 1e15)) return 0;
  return static_cast<std::int64_t>(f);
}

const char* kind_name(AlbedoTexture::Kind kind) {
  switch (kind) {
    case AlbedoTexture::Kind::kConstant:
      return "constant";
    case AlbedoTexture::Kind::kChecker:
      return "checker";
    case AlbedoTexture::Kind::kPatches:
      return "patches";
    case AlbedoTexture::Kind::kNoise:
      return "noise";
  }
  return "?";
}

const char* kind_name(ColourTexture::Kind kind) {
  switch (kind) {
    case ColourTexture::Kind::kConstant:
      return "constant";
    case ColourTexture::Kind::kChecker:
      return "checker";
    case ColourTexture::Kind::kPatches:
      return "patches";
  }
  return "?";
}

nlohmann::json rgb_json(const Vec3& rgb) { return {rgb.x(), rgb.y(), rgb.z()}; }

// HSV (hue in turns, value 1) to linear r, g, b.
Vec3 hsv_rgb(double hue, double saturation) {
  const double h6 = 6.0 * (hue - std::floor(hue));
  const int sector = std::min(5, static_cast<int>(h6));
  const double f = h6 - sector;
  const double p = 1 - saturation, q = 1 - saturation * f, t = 1 - saturation * (1 - f);
  switch (sector) {
    case 0:
      return {1, t, p};
    case 1:
      return {q, 1, p};
    case 2:
      return {p, 1, t};
    case 3:
      return {p, q, 1};
    case 4:
      return {t, p, 1};
    default:
      return {1, p, q};
  }
}

}  // namespace

Vec3 normalised_tint(const Vec3& rgb, const std::string& what) {
  if (!rgb.allFinite() || rgb.minCoeff() < 0) {
    fail("{}: a colour [r, g, b] needs finite values >= 0, got [{}, {}, {}]", what, rgb.x(), rgb.y(),
         rgb.z());
  }
  const double grey = bt601_grey(rgb);
  if (!(grey > 1e-6))
    fail("{}: the colour [{}, {}, {}] is black; it has no hue", what, rgb.x(), rgb.y(), rgb.z());
  return rgb / grey;
}

Vec3 ColourTexture::eval(double x_mm, double y_mm) const {
  switch (kind) {
    case Kind::kConstant:
      return normalised_tint(a, "colour");
    case Kind::kChecker: {
      const auto i = cell(x_mm / period_mm) + cell(y_mm / period_mm);
      return normalised_tint((i % 2 == 0) ? a : b, "colour");
    }
    case Kind::kPatches: {
      // A key apart from the albedo patches': with the same seed and period
      // the cells coincide but hue and albedo are independent.
      const auto ix = static_cast<std::uint64_t>(cell(x_mm / period_mm));
      const auto iy = static_cast<std::uint64_t>(cell(y_mm / period_mm));
      const double hue = hash_unit(seed * 0xc2b2ae3d27d4eb4fULL + ix + 0x51ed27, iy);
      return normalised_tint(hsv_rgb(hue, saturation), "colour");
    }
  }
  return Vec3::Ones();
}

void ColourTexture::check() const {
  normalised_tint(a, kind == Kind::kConstant ? "colour" : "colour: values[0]");
  if (kind == Kind::kChecker) normalised_tint(b, "colour: values[1]");
  if (!(period_mm > 0 && std::isfinite(period_mm))) {
    fail("colour: field 'period_mm' must be positive, got {}", period_mm);
  }
  if (!(saturation >= 0 && saturation <= 1)) {
    fail("colour: field 'saturation' must be in [0, 1], got {}", saturation);
  }
}

nlohmann::json ColourTexture::describe() const {
  nlohmann::json j{{"type", kind_name(kind)}};
  switch (kind) {
    case Kind::kConstant:
      j["value"] = rgb_json(a);
      j["tint"] = rgb_json(normalised_tint(a, "colour"));
      break;
    case Kind::kChecker:
      j["values"] = {rgb_json(a), rgb_json(b)};
      j["tints"] = {rgb_json(normalised_tint(a, "colour")), rgb_json(normalised_tint(b, "colour"))};
      j["period_mm"] = period_mm;
      break;
    case Kind::kPatches:
      j["period_mm"] = period_mm;
      j["saturation"] = saturation;
      j["seed"] = seed;
      break;
  }
  return j;
}

double AlbedoTexture::eval(double x_mm, double y_mm) const {
  switch (kind) {
    case Kind::kConstant:
      return a;
    case Kind::kChecker: {
      const auto i = cell(x_mm / period_mm) + cell(y_mm / period_mm);
      return (i % 2 == 0) ? a : b;
    }
    case Kind::kPatches: {
      const auto ix = static_cast<std::uint64_t>(cell(x_mm / period_mm));
      const auto iy = static_cast<std::uint64_t>(cell(y_mm / period_mm));
      return a + (b - a) * hash_unit(seed * 0x9e3779b97f4a7c15ULL + ix, iy);
    }
    case Kind::kNoise: {
      // Six plane waves of random direction and phase around the wavelength.
      constexpr int kWaves = 6;
      double sum = 0;
      for (int k = 0; k < kWaves; ++k) {
        const auto key = static_cast<std::uint64_t>(k);
        const double angle = 2 * kPi * hash_unit(seed, 3 * key);
        const double wavelength = period_mm * (0.6 + 0.8 * hash_unit(seed, 3 * key + 1));
        const double phase = 2 * kPi * hash_unit(seed, 3 * key + 2);
        const double u = x_mm * std::cos(angle) + y_mm * std::sin(angle);
        sum += std::sin(2 * kPi * u / wavelength + phase);
      }
      const double s = std::clamp(sum / std::sqrt(2.0 * kWaves), -1.0, 1.0);
      return a + (b - a) * (0.5 + 0.5 * s);
    }
  }
  return a;
}

void AlbedoTexture::check() const {
  if (!(a >= 0 && std::isfinite(a))) fail("albedo: field 'a' must be a finite value >= 0, got {}", a);
  if (!(b >= 0 && std::isfinite(b))) fail("albedo: field 'b' must be a finite value >= 0, got {}", b);
  if (!(period_mm > 0 && std::isfinite(period_mm))) {
    fail("albedo: field 'period_mm' must be positive, got {}", period_mm);
  }
}

nlohmann::json AlbedoTexture::describe() const {
  nlohmann::json j{{"type", kind_name(kind)}};
  if (kind == Kind::kConstant) {
    j["value"] = a;
  } else {
    j["values"] = {a, b};
    j["period_mm"] = period_mm;
    if (kind != Kind::kChecker) j["seed"] = seed;
  }
  return j;
}

double Material::shading(double x_mm, double y_mm, const Vec3& n, const Vec3& l, const Vec3& v) const {
  const double cos_l = n.dot(l);
  if (cos_l <= 0) return 0;
  double f = 0;
  if (diffuse && kd != 0) f += kd * albedo.eval(x_mm, y_mm) * diffuse->eval(n, l, v);
  if (specular && ks != 0) f += ks * specular->eval(n, l, v);
  return f * cos_l;
}

nlohmann::json Material::describe() const {
  nlohmann::json j{{"preset", preset}, {"kd", kd}, {"ks", ks}, {"albedo", albedo.describe()}};
  if (colour) j["colour"] = colour->describe();
  j["diffuse"] = diffuse ? diffuse->describe() : "none";
  j["specular"] = specular ? specular->describe() : "none";
  return j;
}

Material parse_material(const std::string& preset, const AlbedoTexture& albedo) {
  const auto spec = parse_preset_string(preset, "material");
  std::set<std::string> used;
  auto get = [&](const std::string& key, double fallback) {
    used.insert(key);
    const auto it = spec.params.find(key);
    return it == spec.params.end() ? fallback : it->second;
  };
  Material m;
  m.preset = preset;
  m.albedo = albedo;
  const std::string& name = spec.name;
  if (name == "lambert") {
    m.kd = get("kd", 1.0);
  } else if (name == "oren-nayar") {
    m.diffuse = std::make_shared<OrenNayar>(get("sigma", 0.3));
    m.kd = get("kd", 1.0);
  } else if (name == "blinn-phong" || name == "cook-torrance" || name == "ward") {
    m.ks = get("ks", 0.5);
    m.kd = get("kd", 1.0 - m.ks);
    if (name == "blinn-phong") {
      m.specular = std::make_shared<BlinnPhong>(get("shininess", 50));
    } else if (name == "cook-torrance") {
      m.specular = std::make_shared<CookTorrance>(get("roughness", 0.3), get("f0", 0.5));
    } else {
      m.specular = std::make_shared<Ward>(get("alpha", 0.2));
    }
  } else if (name == "dielectric") {
    // A smooth dielectric: Wolff's diffuse (darkening at grazing incidence)
    // plus a Cook–Torrance highlight with the same index's f0.
    const double eta = get("eta", 1.5);
    m.diffuse = std::make_shared<WolffDiffuse>(eta);
    m.ks = get("ks", 0.3);
    m.kd = get("kd", 1.0 - m.ks);
    const double f0 = std::pow((eta - 1) / (eta + 1), 2);
    if (m.ks > 0) m.specular = std::make_shared<CookTorrance>(get("roughness", 0.3), f0);
  } else if (name == "two-lobe-ct") {
    // Fig. 2.8(a): k1 Lambert + k2 Cook–Torrance with m = 0.5.
    m.kd = get("k1", 0.5);
    m.ks = get("k2", 0.5);
    m.specular = std::make_shared<CookTorrance>(get("roughness", 0.5), get("f0", 0.5));
  } else if (name == "two-lobe-fabric") {
    m.kd = 0;
    m.diffuse = nullptr;
    m.ks = 1;
    m.specular = std::make_shared<FabricTwoLobe>(get("k1", 0.5), get("k2", 0.5));
  } else if (name == "two-lobe-random") {
    m.kd = 0;
    m.diffuse = nullptr;
    m.ks = 1;
    const double seed = get("seed", 1);
    if (!(seed >= 0 && seed < 9e15)) fail("material '{}': 'seed' must be a non-negative integer", preset);
    m.specular =
        std::make_shared<RandomTwoLobe>(get("k1", 0.5), get("k2", 0.5), static_cast<std::uint64_t>(seed));
  } else if (name == "chrome" || name == "mirror") {
    m.kd = 0;
    m.diffuse = nullptr;
    m.ks = get("reflectance", 1.0);
    m.specular = std::make_shared<Mirror>();
  } else {
    fail(
        "material '{}': unknown preset '{}' (known: lambert, oren-nayar, dielectric, blinn-phong, "
        "cook-torrance, ward, two-lobe-ct, two-lobe-fabric, two-lobe-random, chrome)",
        preset, name);
  }
  if (spec.params.contains("albedo")) {
    used.insert("albedo");
    m.albedo = AlbedoTexture{};
    m.albedo.a = m.albedo.b = spec.params.at("albedo");
  }
  for (const auto& [key, value] : spec.params) {
    if (!used.contains(key)) fail("material '{}': unknown key '{}' for '{}'", preset, key, name);
  }
  if (!(m.kd >= 0)) fail("material '{}': 'kd' must not be negative, got {}", preset, m.kd);
  if (!(m.ks >= 0)) fail("material '{}': 'ks' must not be negative, got {}", preset, m.ks);
  m.albedo.check();
  return m;
}

std::vector<std::string> material_presets() {
  return {"lambert",
          "oren-nayar:sigma=0.3",
          "blinn-phong:shininess=50,ks=0.5",
          "cook-torrance:roughness=0.3,ks=0.5,f0=0.5",
          "ward:alpha=0.2,ks=0.5",
          "dielectric:eta=1.5,ks=0.3,roughness=0.3",
          "two-lobe-ct:k1=0.5,k2=0.5",
          "two-lobe-fabric:k1=0.5,k2=0.5",
          "two-lobe-random:k1=0.5,k2=0.5",
          "chrome"};
}

}  // namespace lightstage::sim
