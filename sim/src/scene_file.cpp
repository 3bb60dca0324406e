#include "lightstage/sim/scene_file.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/printable.hpp"
#include "lightstage/common/yaml_field.hpp"

#include <fmt/format.h>

#include <yaml-cpp/yaml.h>

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>
#include <utility>

namespace lightstage::sim {
namespace {

using Field = YamlField;

HeightField::Footprint parse_footprint(const Field& f, double* size_mm, double default_size) {
  *size_mm = default_size;
  if (!f.is_map()) f.error("expected {shape: square|disk|support, size_mm: ...}");
  f.only_keys({"shape", "size_mm"});
  HeightField::Footprint fp = HeightField::Footprint::kSquare;
  if (f.has("shape")) {
    const auto shape = f["shape"].text();
    if (shape == "square") {
      fp = HeightField::Footprint::kSquare;
    } else if (shape == "disk") {
      fp = HeightField::Footprint::kDisk;
    } else if (shape == "support") {
      fp = HeightField::Footprint::kSupport;
    } else {
      f["shape"].error("must be square, disk or support, got '" + shape + "'");
    }
  }
  if (f.has("size_mm")) *size_mm = f["size_mm"].positive();
  return fp;
}

std::shared_ptr<const Shape> parse_object(const Field& f) {
  const auto type = f["type"].text();
  // Each object type accepts its own keys; anything else is a misspelling.
  auto make_field = [&](std::shared_ptr<const HeightFunction> function, HeightField::Footprint default_fp,
                        double default_size) {
    double size = default_size;
    HeightField::Footprint fp = default_fp;
    if (f.has("footprint")) fp = parse_footprint(f["footprint"], &size, default_size);
    return std::make_shared<HeightField>(std::move(function), fp, size);
  };
  try {
    if (type == "sphere") {
      f.only_keys({"type", "radius_mm", "center_mm"});
      const Vec3 center = f.has("center_mm") ? f["center_mm"].vec3() : Vec3::Zero();
      return std::make_shared<Sphere>(center, f["radius_mm"].positive());
    }
    if (type == "bumps") {
      f.only_keys({"type", "size_mm", "bumps", "footprint"});
      const double size = f.has("size_mm") ? f["size_mm"].positive() : 90.0;
      std::vector<GaussianBumps::Bump> bumps;
      const Field list = f["bumps"];
      for (std::size_t i = 0; i < list.size(); ++i) {
        const Field b = list.at(i);
        b.only_keys({"center_mm", "height_mm", "sigma_mm"});
        bumps.push_back({b["center_mm"].vec2(), b["height_mm"].non_negative(), b["sigma_mm"].positive()});
      }
      return make_field(std::make_shared<GaussianBumps>(std::move(bumps), size / 2),
                        HeightField::Footprint::kSquare, size);
    }
    if (type == "relief") {
      f.only_keys({"type", "size_mm", "height_mm", "bevel_mm", "footprint"});
      const double size = f.has("size_mm") ? f["size_mm"].positive() : 90.0;
      const double height = f.has("height_mm") ? f["height_mm"].positive() : 3.0;
      const double bevel = f.has("bevel_mm") ? f["bevel_mm"].positive() : 0.8;
      return make_field(std::make_shared<Relief>(size, height, bevel), HeightField::Footprint::kSquare, size);
    }
    if (type == "blob") {
      f.only_keys({"type", "size_mm", "footprint"});
      const double size = f.has("size_mm") ? f["size_mm"].positive() : 90.0;
      return make_field(std::make_shared<Blob>(size), HeightField::Footprint::kSupport, size);
    }
  } catch (const InputError& e) {
    const std::string what = e.what();
    if (what.find("field '") != std::string::npos) throw;
    f.error(what);  // a constructor's check: name the object's position
  }
  f["type"].error("must be sphere, bumps, relief or blob, got '" + type + "'");
}

AlbedoTexture parse_albedo(const Field& f) {
  AlbedoTexture t;
  if (f.is_scalar()) {
    t.a = t.b = f.non_negative();
    return t;
  }
  f.only_keys({"type", "value", "values", "period_mm", "seed"});
  const auto type = f["type"].text();
  if (type == "constant") {
    t.a = t.b = f["value"].non_negative();
    return t;
  }
  if (type == "checker") {
    t.kind = AlbedoTexture::Kind::kChecker;
  } else if (type == "patches") {
    t.kind = AlbedoTexture::Kind::kPatches;
  } else if (type == "noise") {
    t.kind = AlbedoTexture::Kind::kNoise;
  } else {
    f["type"].error("must be constant, checker, patches or noise, got '" + type + "'");
  }
  if (f.has("values")) {
    const Field v = f["values"];
    if (v.size() != 2) v.error("expected [low, high]");
    t.a = v.at(0).non_negative();
    t.b = v.at(1).non_negative();
  } else {
    t.a = 0.2;
    t.b = 0.9;
  }
  if (f.has("period_mm")) t.period_mm = f["period_mm"].positive();
  if (f.has("seed")) {
    const int seed = f["seed"].integer();
    if (seed < 0) f["seed"].error("must not be negative");
    t.seed = static_cast<std::uint64_t>(seed);
  }
  return t;
}

// [r, g, b] (a list) or "r,g,b" (a plain scalar): not negative, not black.
Vec3 parse_rgb(const Field& f) {
  Vec3 rgb;
  if (f.is_scalar()) {
    const std::string text = f.text();
    std::istringstream in(text);
    std::string part;
    std::vector<double> values;
    while (std::getline(in, part, ',')) {
      char* end = nullptr;
      const double v = std::strtod(part.c_str(), &end);
      const std::string rest = end == nullptr ? part : std::string(end);
      if (end == part.c_str() || rest.find_first_not_of(" \t") != std::string::npos) {
        f.error("cannot read '" + printable(part) + "' of '" + printable(text) +
                "' as a number (a colour is r,g,b or [r, g, b])");
      }
      values.push_back(v);
    }
    if (values.size() != 3 || text.back() == ',')
      f.error("expected a colour r,g,b (or [r, g, b]), got '" + printable(text) + "'");
    rgb = Vec3(values[0], values[1], values[2]);
  } else {
    if (f.size() != 3) f.error("expected a colour [r, g, b]");
    rgb = Vec3(f.at(0).number(), f.at(1).number(), f.at(2).number());
  }
  for (int i = 0; i < 3; ++i) {
    if (!(rgb[i] >= 0 && std::isfinite(rgb[i]))) {
      f.error(
          fmt::format("colour values must be finite and >= 0, got [{}, {}, {}]", rgb.x(), rgb.y(), rgb.z()));
    }
  }
  if (!(bt601_grey(rgb) > 1e-6))
    f.error(fmt::format("the colour [{}, {}, {}] is black: it has no hue", rgb.x(), rgb.y(), rgb.z()));
  return rgb;
}

// The `colour` key (and the --colour spec): [r, g, b], "r,g,b", a type name
// (its defaults) or a mapping {type: constant | checker | patches, ...}.
ColourTexture parse_colour_field(const Field& f) {
  ColourTexture t;
  std::string type;
  if (f.is_map()) {
    f.only_keys({"type", "value", "values", "period_mm", "saturation", "seed"});
    type = f["type"].text();
  } else if (f.is_scalar() && !f.text().empty() &&
             std::isalpha(static_cast<unsigned char>(f.text().front())) != 0) {
    type = f.text();
    if (type != "checker" && type != "patches") {
      f.error("must be a colour [r, g, b], r,g,b, checker, patches or a mapping {type: ...}, got '" + type +
              "'");
    }
  } else {
    t.a = t.b = parse_rgb(f);
    return t;
  }
  // Keys that only some types take: given with another, they would be ignored.
  auto only_for = [&](const std::string& key, const std::set<std::string>& types) {
    if (f.is_map() && f.has(key) && !types.contains(type)) {
      std::string list;
      for (const auto& name : types) list += (list.empty() ? "" : " or ") + name;
      f[key].error("applies to type " + list + " only, not '" + type + "'");
    }
  };
  if (type == "constant") {
    t.kind = ColourTexture::Kind::kConstant;
  } else if (type == "checker") {
    t.kind = ColourTexture::Kind::kChecker;
  } else if (type == "patches") {
    t.kind = ColourTexture::Kind::kPatches;
  } else {
    f["type"].error("must be constant, checker or patches, got '" + type + "'");
  }
  only_for("value", {"constant"});
  only_for("values", {"checker"});
  only_for("period_mm", {"checker", "patches"});
  only_for("saturation", {"patches"});
  only_for("seed", {"patches"});
  if (t.kind == ColourTexture::Kind::kConstant) {
    t.a = t.b = parse_rgb(f["value"]);
    return t;
  }
  if (t.kind == ColourTexture::Kind::kChecker) {
    t.a = Vec3(0.9, 0.3, 0.3);
    t.b = Vec3(0.3, 0.3, 0.9);
    if (f.is_map() && f.has("values")) {
      const Field v = f["values"];
      if (v.size() != 2) v.error("expected two colours [[r, g, b], [r, g, b]]");
      t.a = parse_rgb(v.at(0));
      t.b = parse_rgb(v.at(1));
    }
  }
  if (f.is_map() && f.has("period_mm")) t.period_mm = f["period_mm"].positive();
  if (f.is_map() && f.has("saturation")) {
    t.saturation = f["saturation"].number();
    if (!(t.saturation >= 0 && t.saturation <= 1))
      f["saturation"].error(fmt::format("must be in [0, 1], got {}", t.saturation));
  }
  if (f.is_map() && f.has("seed")) {
    const int seed = f["seed"].integer();
    if (seed < 0) f["seed"].error(fmt::format("must not be negative, got {}", seed));
    t.seed = static_cast<std::uint64_t>(seed);
  }
  t.check();
  return t;
}

CameraOverrides parse_camera(const Field& f) {
  f.only_keys({"model", "width", "height", "pixel_pitch_mm", "focal_px", "position_mm"});
  CameraOverrides c;
  if (f.has("model")) {
    const auto model = f["model"].text();
    if (model == "orthographic") {
      c.model = CameraModel::kOrthographic;
    } else if (model == "pinhole") {
      c.model = CameraModel::kPinhole;
    } else {
      f["model"].error("must be 'orthographic' or 'pinhole', got '" + model + "'");
    }
  }
  if (f.has("width")) {
    c.width = f["width"].integer();
    if (*c.width <= 0 || *c.width > 16384) f["width"].error("must be in 1..16384");
  }
  if (f.has("height")) {
    c.height = f["height"].integer();
    if (*c.height <= 0 || *c.height > 16384) f["height"].error("must be in 1..16384");
  }
  if (f.has("pixel_pitch_mm")) c.pixel_pitch_mm = f["pixel_pitch_mm"].positive();
  if (f.has("focal_px")) c.focal_px = f["focal_px"].positive();
  if (f.has("position_mm")) c.position_mm = f["position_mm"].vec3();
  return c;
}

Scene parse_document(const Field& root, const std::string& source) {
  if (!root.is_map()) root.error("a scene file is a YAML mapping");
  root.only_keys({"name", "object", "material", "albedo", "colour", "camera", "led_radius_mm", "led_radiance",
                  "highlight_blur_px", "cast_shadows", "environment_radiance"});
  Scene scene;
  scene.name = root.has("name") ? root["name"].text() : source;
  scene.shape = parse_object(root["object"]);
  const AlbedoTexture albedo = root.has("albedo") ? parse_albedo(root["albedo"]) : AlbedoTexture{};
  const std::string material = root.has("material") ? root["material"].text() : "lambert";
  try {
    scene.material = parse_material(material, albedo);
  } catch (const InputError& e) {
    root["material"].error(e.what());
  }
  if (root.has("colour")) scene.material.colour = parse_colour_field(root["colour"]);
  if (root.has("camera")) scene.camera = parse_camera(root["camera"]);
  if (root.has("led_radius_mm")) scene.led_radius_mm = root["led_radius_mm"].positive();
  if (root.has("led_radiance")) scene.led_radiance = root["led_radiance"].non_negative();
  if (root.has("highlight_blur_px")) {
    scene.highlight_blur_px = root["highlight_blur_px"].non_negative();
    if (scene.highlight_blur_px > 20) root["highlight_blur_px"].error("must be at most 20 pixels");
  }
  if (root.has("cast_shadows")) scene.cast_shadows = root["cast_shadows"].boolean();
  if (root.has("environment_radiance"))
    scene.environment_radiance = root["environment_radiance"].non_negative();
  return scene;
}

// Sized for the default rig camera (512 px at 0.2 mm: a 102 mm field).
const std::vector<std::pair<std::string, std::string>>& presets() {
  static const std::vector<std::pair<std::string, std::string>> kPresets = {
      {"sphere", R"(name: sphere
object: {type: sphere, radius_mm: 40}
material: lambert
albedo: 1.0
)"},
      {"chrome-sphere", R"(name: chrome-sphere
object: {type: sphere, radius_mm: 40}
material: chrome
)"},
      {"chrome-probe", R"(name: chrome-probe
object: {type: sphere, radius_mm: 40}
material: chrome
environment_radiance: 0.05
)"},
      {"white-target", R"(name: white-target
object: {type: bumps, size_mm: 100, bumps: []}
material: lambert
albedo: 0.9
)"},
      {"matte-sphere", R"(name: matte-sphere
object: {type: sphere, radius_mm: 40}
material: lambert
albedo: 0.5
)"},
      {"shiny-sphere", R"(name: shiny-sphere
object: {type: sphere, radius_mm: 40}
material: "cook-torrance:roughness=0.3,ks=0.5,f0=0.5"
albedo: {type: patches, values: [0.3, 0.9], period_mm: 16, seed: 3}
)"},
      {"bumps", R"(name: bumps
object:
  type: bumps
  size_mm: 96
  bumps:
    - {center_mm: [0, 0], height_mm: 12, sigma_mm: 10}
    - {center_mm: [-25, 22], height_mm: 8, sigma_mm: 7}
    - {center_mm: [26, 20], height_mm: 6, sigma_mm: 9}
    - {center_mm: [-22, -26], height_mm: 10, sigma_mm: 6}
    - {center_mm: [24, -24], height_mm: 5, sigma_mm: 12}
    - {center_mm: [0, 34], height_mm: 4, sigma_mm: 4}
    - {center_mm: [34, 0], height_mm: 7, sigma_mm: 5}
material: lambert
albedo: 0.8
)"},
      {"relief", R"(name: relief
object: {type: relief, size_mm: 96, height_mm: 3, bevel_mm: 0.8}
material: lambert
albedo: 0.8
)"},
      {"bunny", R"(name: bunny
object: {type: blob, size_mm: 96}
material: lambert
albedo: {type: noise, values: [0.55, 0.9], period_mm: 20, seed: 7}
)"},
      // The robust family's test objects: the bunny standing on a floor, so
      // its ears, head and body cast long shadows on itself and the floor.
      {"bunny-shadows", R"(name: bunny-shadows
object: {type: blob, size_mm: 96, footprint: {shape: square, size_mm: 96}}
material: lambert
albedo: 0.8
cast_shadows: true
)"},
      // The same with a sharp specular lobe on top of the diffuse one.
      {"bunny-specular", R"(name: bunny-specular
object: {type: blob, size_mm: 96, footprint: {shape: square, size_mm: 96}}
material: "cook-torrance:roughness=0.1,ks=0.3,f0=0.9"
albedo: 0.8
cast_shadows: true
)"},
  };
  return kPresets;
}

}  // namespace

Scene parse_scene(const std::string& yaml_text, const std::string& source) {
  return parse_yaml(yaml_text, source, [&](const Field& root) { return parse_document(root, source); });
}

ColourTexture parse_colour(const std::string& spec) {
  const std::string source = fmt::format("colour '{}'", printable(spec));
  if (spec.empty()) fail("{}: empty (give r,g,b, [r, g, b], checker, patches or {{type: ...}})", source);
  return parse_yaml(spec, source, [](const Field& root) { return parse_colour_field(root); });
}

Scene load_scene(const std::filesystem::path& path) {
  return parse_scene(read_text_file(path, "scene file"), path.string());
}

std::vector<std::string> scene_presets() {
  std::vector<std::string> names;
  for (const auto& [name, yaml] : presets()) names.push_back(name);
  return names;
}

std::string scene_preset_yaml(const std::string& name) {
  for (const auto& [preset, yaml] : presets()) {
    if (preset == name) return yaml;
  }
  std::string known;
  for (const auto& n : scene_presets()) known += (known.empty() ? "" : ", ") + n;
  fail("unknown scene preset '{}' (known: {}; or give a path to a scene .yaml file)", name, known);
}

Scene resolve_scene(const std::string& name_or_path) {
  for (const auto& [preset, yaml] : presets()) {
    if (preset == name_or_path) {
      Scene scene = parse_scene(yaml, "preset " + preset);
      scene.name = preset;
      return scene;
    }
  }
  if (name_or_path.find('/') != std::string::npos || name_or_path.ends_with(".yaml") ||
      name_or_path.ends_with(".yml") || std::filesystem::exists(name_or_path)) {
    return load_scene(name_or_path);
  }
  scene_preset_yaml(name_or_path);  // throws, listing the presets
  fail("unknown scene '{}'", name_or_path);
}

}  // namespace lightstage::sim
