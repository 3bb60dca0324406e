#include "lightstage/host/calibration/light_calibration.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/printable.hpp"
#include "util/atomic_file.hpp"

#include <fmt/format.h>

#include <cmath>
#include <fstream>

namespace lightstage::calibration {
namespace {

using nlohmann::json;

json vec3_json(const Vec3& v) { return json::array({v.x(), v.y(), v.z()}); }

// Field readers that name "<source>: <path>" when a value is missing or wrong.
const json& member(const json& j, const char* key, const std::string& where) {
  const auto it = j.find(key);
  if (it == j.end()) fail("{}.{}: missing", where, key);
  return *it;
}

Vec3 vec3_value(const json& v, const std::string& where) {
  if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number())
    fail("{}: expected [x, y, z], got {}", where, printable(v.dump()));
  const Vec3 result(v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
  if (!result.allFinite()) fail("{}: not finite", where);
  return result;
}

double number_value(const json& v, const std::string& where) {
  if (!v.is_number()) fail("{}: expected a number, got {}", where, printable(v.dump()));
  const double value = v.get<double>();
  if (!std::isfinite(value)) fail("{}: not a finite number", where);
  return value;
}

std::string string_value(const json& v, const std::string& where) {
  if (!v.is_string()) fail("{}: expected a string, got {}", where, printable(v.dump()));
  return v.get<std::string>();
}

json light_json(const CalibratedLight& light) {
  json j{{"image", light.image},
         {"led_id", light.led_id},
         {"measured", light.measured},
         {"direction", vec3_json(light.direction)},
         {"elevation_deg", deg_from_rad(std::asin(std::clamp(light.direction.z(), -1.0, 1.0)))},
         {"azimuth_deg", deg_from_rad(std::atan2(light.direction.y(), light.direction.x()))},
         {"intensity", light.intensity}};
  if (light.position_mm) {
    j["position_mm"] = vec3_json(*light.position_mm);
    j["position_residual_mm"] = light.position_residual_mm;
    if (light.position_sigma_mm) j["position_sigma_mm"] = *light.position_sigma_mm;
    if (light.reprojection_rms_px) j["reprojection_rms_px"] = *light.reprojection_rms_px;
  }
  if (light.intensity_residual) j["intensity_residual"] = *light.intensity_residual;
  if (light.nominal_position_mm) j["nominal_position_mm"] = vec3_json(*light.nominal_position_mm);
  json observations = json::array();
  for (const auto& o : light.observations) {
    json entry{{"sphere", o.sphere}, {"highlight", o.highlight.to_json()}};
    if (o.reflection) {
      entry["surface_point_mm"] = vec3_json(o.reflection->point_mm);
      entry["normal"] = vec3_json(o.reflection->normal);
      entry["mirror_direction"] = vec3_json(o.reflection->direction);
    }
    observations.push_back(std::move(entry));
  }
  j["observations"] = std::move(observations);
  return j;
}

}  // namespace

bool LightCalibration::has_positions() const {
  for (const auto& light : lights) {
    if (light.measured && !light.position_mm) return false;
  }
  return !lights.empty();
}

json to_json(const LightCalibration& c) {
  json spheres = json::array();
  for (const auto& s : c.spheres) {
    json entry = s.sphere.to_json();
    entry["stack"] = s.stack.string();
    spheres.push_back(std::move(entry));
  }
  json lights = json::array();
  for (const auto& light : c.lights) lights.push_back(light_json(light));
  json j{{"format", kCalibrationFormat},
         {"version", kCalibrationVersion},
         {"software", c.software},
         {"created", c.created},
         {"rig", c.rig},
         {"camera", c.camera.to_json()},
         {"object_position_mm", vec3_json(c.object_position_mm)},
         {"direction_method", c.direction_method},
         {"spheres", spheres},
         {"intensity_source", c.intensity_source},
         {"problems", c.problems},
         {"lights", lights}};
  if (c.dome_radius_mm) j["dome_radius_mm"] = *c.dome_radius_mm;
  if (c.nominal_fit) j["nominal_fit"] = c.nominal_fit->to_json();
  return j;
}

LightCalibration calibration_from_json(const json& j, const std::string& source) {
  if (!j.is_object()) fail("{}: expected a JSON object at the top level", source);
  const std::string format = string_value(member(j, "format", source), source + ": format");
  if (format != kCalibrationFormat)
    fail("{}: format: expected \"{}\", got \"{}\"", source, kCalibrationFormat, format);
  const json& version = member(j, "version", source);
  if (!version.is_number_integer() || version.get<long long>() < 1 ||
      version.get<long long>() > kCalibrationVersion) {
    fail("{}: version: unsupported value {} (this build reads 1..{})", source, printable(version.dump()),
         kCalibrationVersion);
  }
  LightCalibration c;
  c.camera = CameraGeometry::from_json(member(j, "camera", source), source + ": camera");
  c.object_position_mm = vec3_value(member(j, "object_position_mm", source), source + ": object_position_mm");
  if (const auto it = j.find("direction_method"); it != j.end())
    c.direction_method = string_value(*it, source + ": direction_method");
  if (const auto it = j.find("rig"); it != j.end() && !it->is_null())
    c.rig = string_value(*it, source + ": rig");
  if (const auto it = j.find("dome_radius_mm"); it != j.end() && !it->is_null())
    c.dome_radius_mm = number_value(*it, source + ": dome_radius_mm");
  if (const auto it = j.find("intensity_source"); it != j.end()) c.intensity_source = *it;
  const json& lights = member(j, "lights", source);
  if (!lights.is_array() || lights.empty())
    fail("{}: lights: expected a non-empty array, got {}", source,
         lights.is_array() ? "[]" : lights.type_name());
  for (std::size_t i = 0; i < lights.size(); ++i) {
    const std::string where = fmt::format("{}: lights[{}]", source, i);
    const json& entry = lights[i];
    if (!entry.is_object()) fail("{}: expected an object, got {}", where, entry.type_name());
    CalibratedLight light;
    light.image = string_value(member(entry, "image", where), where + ".image");
    if (const auto it = entry.find("led_id"); it != entry.end() && !it->is_null()) {
      if (!it->is_number_integer() || it->get<long long>() < -1 || it->get<long long>() > 1000000)
        fail("{}.led_id: expected an integer id, got {}", where, printable(it->dump()));
      light.led_id = it->get<int>();
    }
    const json& measured = member(entry, "measured", where);
    if (!measured.is_boolean())
      fail("{}.measured: expected true or false, got {}", where, printable(measured.dump()));
    light.measured = measured.get<bool>();
    light.direction = vec3_value(member(entry, "direction", where), where + ".direction");
    if (light.measured && std::abs(light.direction.norm() - 1) > 1e-3)
      fail("{}.direction: expected a unit vector, got length {}", where, light.direction.norm());
    if (const auto it = entry.find("position_mm"); it != entry.end() && !it->is_null())
      light.position_mm = vec3_value(*it, where + ".position_mm");
    if (const auto it = entry.find("position_residual_mm"); it != entry.end())
      light.position_residual_mm = number_value(*it, where + ".position_residual_mm");
    if (const auto it = entry.find("position_sigma_mm"); it != entry.end() && !it->is_null())
      light.position_sigma_mm = number_value(*it, where + ".position_sigma_mm");
    if (const auto it = entry.find("reprojection_rms_px"); it != entry.end() && !it->is_null())
      light.reprojection_rms_px = number_value(*it, where + ".reprojection_rms_px");
    light.intensity = number_value(member(entry, "intensity", where), where + ".intensity");
    if (!(light.intensity > 0)) fail("{}.intensity: must be positive, got {}", where, light.intensity);
    if (const auto it = entry.find("nominal_position_mm"); it != entry.end() && !it->is_null())
      light.nominal_position_mm = vec3_value(*it, where + ".nominal_position_mm");
    c.lights.push_back(std::move(light));
  }
  if (const auto it = j.find("problems"); it != j.end() && it->is_array()) {
    for (const auto& p : *it) {
      if (p.is_string()) c.problems.push_back(p.get<std::string>());
    }
  }
  if (const auto it = j.find("created"); it != j.end() && it->is_string()) c.created = it->get<std::string>();
  if (const auto it = j.find("software"); it != j.end() && it->is_string())
    c.software = it->get<std::string>();
  return c;
}

void write_calibration(const std::filesystem::path& path, const LightCalibration& calibration) {
  util::write_text_atomic(path, to_json(calibration).dump(2) + "\n");
}

LightCalibration read_calibration(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) fail("{}: cannot open for reading", path.string());
  json j;
  try {
    j = json::parse(in);
  } catch (const json::exception& e) {
    fail("{}: not valid JSON: {}", path.string(), printable(e.what(), 4 * kPrintableChars));
  }
  return calibration_from_json(j, path.string());
}

std::string directions_text(const LightCalibration& calibration) {
  std::string text;
  for (const auto& light : calibration.lights) {
    if (light.measured)
      text += fmt::format("{:.9f} {:.9f} {:.9f}\n", light.direction.x(), light.direction.y(),
                          light.direction.z());
  }
  return text;
}

std::string intensities_text(const LightCalibration& calibration) {
  std::string text;
  for (const auto& light : calibration.lights) {
    if (light.measured)
      text += fmt::format("{:.9f} {:.9f} {:.9f}\n", light.intensity, light.intensity, light.intensity);
  }
  return text;
}

}  // namespace lightstage::calibration
