#include "io/stack_manifest.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/version.hpp"
#include "util/utc_time.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>

namespace lightstage::io {
namespace {

using nlohmann::json;

json vec3_json(const Vec3& v) { return json::array({v.x(), v.y(), v.z()}); }

const char* const kReservedKeys[] = {"format", "version", "software",     "created", "width",
                                     "height", "mask",    "ground_truth", "frames"};

double number_field(const json& entry, const char* key, double fallback, const std::filesystem::path& path,
                    std::size_t index) {
  const auto it = entry.find(key);
  if (it == entry.end() || it->is_null()) return fallback;
  if (!it->is_number())
    fail("{}: frames[{}].{}: expected a number, got {}", path.string(), index, key, it->dump());
  const double value = it->get<double>();
  if (!std::isfinite(value)) fail("{}: frames[{}].{}: not a finite number", path.string(), index, key);
  return value;
}

}  // namespace

json build_manifest(const ImageStack& stack, const StackFiles& files, const json& extra) {
  if (!extra.is_object()) fail("extra_manifest: expected a JSON object, got {}", extra.type_name());
  json frames = json::array();
  for (std::size_t i = 0; i < stack.frames.size(); ++i) {
    const Frame& frame = stack.frames[i];
    json entry = {{"index", i},
                  {"file", files.frames.at(i)},
                  {"led_id", frame.led_id},
                  {"light_direction", vec3_json(frame.light_direction)},
                  {"light_intensity", vec3_json(frame.light_intensity)}};
    if (frame.led_position_mm) entry["led_position_mm"] = vec3_json(*frame.led_position_mm);
    entry["exposure_us"] = frame.exposure_us;
    entry["gain"] = frame.gain;
    entry["black_level"] = frame.black_level;
    entry["saturation_level"] = frame.saturation_level;
    if (!frame.dark_file.empty()) entry["dark"] = frame.dark_file;
    frames.push_back(std::move(entry));
  }
  if (const auto extra_frames = extra.find("frames"); extra_frames != extra.end()) {
    if (!extra_frames->is_array() || extra_frames->size() != frames.size()) {
      fail("extra_manifest.frames: expected an array of {} objects (one per frame)", frames.size());
    }
    for (std::size_t i = 0; i < frames.size(); ++i) {
      const json& more = (*extra_frames)[i];
      if (!more.is_object())
        fail("extra_manifest.frames[{}]: expected an object, got {}", i, more.type_name());
      for (const auto& [key, value] : more.items()) {
        if (frames[i].contains(key)) fail("extra_manifest.frames[{}].{}: reserved key", i, key);
        frames[i][key] = value;
      }
    }
  }

  json manifest = {{"format", kStackFormat},
                   {"version", kStackFormatVersion},
                   {"software", std::string("lightstage ") + kVersion},
                   {"created", util::utc_timestamp()},
                   {"width", stack.width()},
                   {"height", stack.height()},
                   {"mask", files.mask.empty() ? json(nullptr) : json(files.mask)}};
  json ground_truth = json::object();
  if (!files.normals.empty()) ground_truth["normals"] = files.normals;
  if (!files.depth.empty()) ground_truth["depth"] = files.depth;
  if (!ground_truth.empty()) manifest["ground_truth"] = ground_truth;
  for (const auto& [key, value] : extra.items()) {
    if (key == "frames") continue;
    for (const char* reserved : kReservedKeys) {
      if (key == reserved) fail("extra_manifest.{}: reserved key, written by write_stack itself", key);
    }
    manifest[key] = value;
  }
  manifest["frames"] = std::move(frames);
  return manifest;
}

void apply_manifest(const std::filesystem::path& path, ImageStack& stack) {
  std::ifstream in(path);
  if (!in) fail("{}: cannot open for reading", path.string());
  json manifest;
  try {
    manifest = json::parse(in);
  } catch (const json::exception& e) {
    fail("{}: not valid JSON: {}", path.string(), e.what());
  }
  if (!manifest.is_object()) fail("{}: expected a JSON object at the top level", path.string());
  if (const auto format = manifest.find("format"); format != manifest.end()) {
    if (!format->is_string() || format->get<std::string>() != kStackFormat) {
      fail("{}: format: expected \"{}\", got {}", path.string(), kStackFormat, format->dump());
    }
  }
  if (const auto version = manifest.find("version"); version != manifest.end()) {
    if (!version->is_number_integer() || version->get<int>() < 1 ||
        version->get<int>() > kStackFormatVersion) {
      fail("{}: version: unsupported value {} (this build reads 1..{})", path.string(), version->dump(),
           kStackFormatVersion);
    }
  }
  const auto frames = manifest.find("frames");
  if (frames == manifest.end()) return;
  if (!frames->is_array()) fail("{}: frames: expected an array, got {}", path.string(), frames->type_name());
  if (frames->size() != stack.frames.size()) {
    fail("{}: frames: {} entries, but filenames.txt lists {} images", path.string(), frames->size(),
         stack.frames.size());
  }
  for (std::size_t i = 0; i < stack.frames.size(); ++i) {
    const json& entry = (*frames)[i];
    Frame& frame = stack.frames[i];
    if (!entry.is_object())
      fail("{}: frames[{}]: expected an object, got {}", path.string(), i, entry.type_name());
    if (const auto file = entry.find("file"); file != entry.end()) {
      if (!file->is_string() || file->get<std::string>() != frame.filename) {
        fail("{}: frames[{}].file: {} does not match '{}' from filenames.txt", path.string(), i, file->dump(),
             frame.filename);
      }
    }
    if (const auto led = entry.find("led_id"); led != entry.end() && !led->is_null()) {
      if (!led->is_number_integer()) {
        fail("{}: frames[{}].led_id: expected an integer, got {}", path.string(), i, led->dump());
      }
      frame.led_id = led->get<int>();
    }
    if (const auto position = entry.find("led_position_mm");
        position != entry.end() && !position->is_null()) {
      if (!position->is_array() || position->size() != 3 || !(*position)[0].is_number() ||
          !(*position)[1].is_number() || !(*position)[2].is_number()) {
        fail("{}: frames[{}].led_position_mm: expected [x, y, z], got {}", path.string(), i,
             position->dump());
      }
      frame.led_position_mm =
          Vec3((*position)[0].get<double>(), (*position)[1].get<double>(), (*position)[2].get<double>());
    }
    frame.exposure_us = number_field(entry, "exposure_us", frame.exposure_us, path, i);
    frame.gain = number_field(entry, "gain", frame.gain, path, i);
    frame.black_level = number_field(entry, "black_level", frame.black_level, path, i);
    frame.saturation_level = number_field(entry, "saturation_level", frame.saturation_level, path, i);
    if (frame.exposure_us < 0)
      fail("{}: frames[{}].exposure_us: negative value {}", path.string(), i, frame.exposure_us);
    if (frame.gain <= 0) fail("{}: frames[{}].gain: must be positive, got {}", path.string(), i, frame.gain);
    if (frame.saturation_level < 0) {
      fail("{}: frames[{}].saturation_level: negative value {}", path.string(), i, frame.saturation_level);
    }
    if (const auto dark = entry.find("dark"); dark != entry.end() && !dark->is_null()) {
      if (!dark->is_string())
        fail("{}: frames[{}].dark: expected a file name, got {}", path.string(), i, dark->dump());
      const std::string name = dark->get<std::string>();
      const std::filesystem::path relative(name);
      if (name.empty() || relative.is_absolute() ||
          std::any_of(relative.begin(), relative.end(),
                      [](const std::filesystem::path& part) { return part == ".."; })) {
        fail("{}: frames[{}].dark: '{}' must name a file inside the stack folder", path.string(), i, name);
      }
      frame.dark_file = name;
    }
  }
}

}  // namespace lightstage::io
