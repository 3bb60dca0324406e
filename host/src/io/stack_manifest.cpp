#include "io/stack_manifest.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/printable.hpp"
#include "lightstage/common/version.hpp"
#include "util/utc_time.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <string>

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
    fail("{}: frames[{}].{}: expected a number, got {}", path.string(), index, key, printable(it->dump()));
  const double value = it->get<double>();
  if (!std::isfinite(value)) fail("{}: frames[{}].{}: not a finite number", path.string(), index, key);
  return value;
}

// The keys build_manifest writes for a frame; any other key of an entry is extra.
const char* const kFrameKeys[] = {"index",
                                  "file",
                                  "led_id",
                                  "light_direction",
                                  "light_intensity",
                                  "led_position_mm",
                                  "exposure_us",
                                  "gain",
                                  "black_level",
                                  "saturation_level",
                                  "dark"};

// A file name from the manifest that must stay inside the stack folder.
std::string folder_file(const json& value, const std::string& field, const std::filesystem::path& path) {
  if (!value.is_string())
    fail("{}: {}: expected a file name, got {}", path.string(), field, printable(value.dump()));
  const std::string name = value.get<std::string>();
  const std::filesystem::path relative(name);
  if (name.empty() || relative.is_absolute() ||
      std::any_of(relative.begin(), relative.end(),
                  [](const std::filesystem::path& part) { return part == ".."; })) {
    fail("{}: {}: '{}' must name a file inside the stack folder", path.string(), field, printable(name));
  }
  return name;
}

double number_value(const json& value, const std::string& field, const std::filesystem::path& path) {
  if (!value.is_number())
    fail("{}: {}: expected a number, got {}", path.string(), field, printable(value.dump()));
  const double number = value.get<double>();
  if (!std::isfinite(number)) fail("{}: {}: not a finite number", path.string(), field);
  return number;
}

int integer_field(const json& value, const std::string& field, const std::filesystem::path& path) {
  if (!value.is_number_integer())
    fail("{}: {}: expected an integer, got {}", path.string(), field, printable(value.dump()));
  return value.get<int>();
}

std::vector<double> numbers_field(const json& value, const std::string& field,
                                  const std::filesystem::path& path) {
  if (!value.is_array())
    fail("{}: {}: expected an array of numbers, got {}", path.string(), field, printable(value.dump()));
  std::vector<double> numbers;
  for (std::size_t k = 0; k < value.size(); ++k)
    numbers.push_back(number_value(value[k], fmt::format("{}[{}]", field, k), path));
  return numbers;
}

Vec3 vec3_field(const json& value, const std::string& field, const std::filesystem::path& path) {
  const std::vector<double> v = numbers_field(value, field, path);
  if (v.size() != 3) fail("{}: {}: must have 3 numbers, got {}", path.string(), field, v.size());
  return Vec3(v[0], v[1], v[2]);
}

int led_id_key(const std::string& key, const std::string& field, const std::filesystem::path& path) {
  int id = 0;
  const auto [end, error] = std::from_chars(key.data(), key.data() + key.size(), id);
  if (error != std::errc() || end != key.data() + key.size() || key.empty())
    fail("{}: {}: the key '{}' is not an LED id", path.string(), field, key);
  return id;
}

double number_key(const std::string& key, const std::string& field, const std::filesystem::path& path) {
  double number = 0;
  const auto [end, error] = std::from_chars(key.data(), key.data() + key.size(), number);
  if (error != std::errc() || end != key.data() + key.size() || key.empty() || !std::isfinite(number))
    fail("{}: {}: the key '{}' is not a number", path.string(), field, key);
  return number;
}

// The fields of frame entry `i` that load_stack and resume read alike: LED id
// and position, exposure, gain, levels and the dark frame's file.
void read_frame_fields(const json& entry, Frame& frame, const std::filesystem::path& path, std::size_t i) {
  if (const auto led = entry.find("led_id"); led != entry.end() && !led->is_null()) {
    if (!led->is_number_integer()) {
      fail("{}: frames[{}].led_id: expected an integer, got {}", path.string(), i, printable(led->dump()));
    }
    frame.led_id = led->get<int>();
  }
  if (const auto position = entry.find("led_position_mm"); position != entry.end() && !position->is_null()) {
    if (!position->is_array() || position->size() != 3 || !(*position)[0].is_number() ||
        !(*position)[1].is_number() || !(*position)[2].is_number()) {
      fail("{}: frames[{}].led_position_mm: expected [x, y, z], got {}", path.string(), i,
           printable(position->dump()));
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
  if (const auto dark = entry.find("dark"); dark != entry.end() && !dark->is_null())
    frame.dark_file = folder_file(*dark, fmt::format("frames[{}].dark", i), path);
}

}  // namespace

json read_manifest_json(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) fail("{}: cannot open for reading", path.string());
  json manifest;
  try {
    manifest = json::parse(in);
  } catch (const json::exception& e) {
    fail("{}: not valid JSON: {}", path.string(), printable(e.what(), 4 * kPrintableChars));
  }
  if (!manifest.is_object()) fail("{}: expected a JSON object at the top level", path.string());
  if (const auto format = manifest.find("format"); format != manifest.end()) {
    if (!format->is_string() || format->get<std::string>() != kStackFormat) {
      fail("{}: format: expected \"{}\", got {}", path.string(), kStackFormat, printable(format->dump()));
    }
  }
  if (const auto version = manifest.find("version"); version != manifest.end()) {
    if (!version->is_number_integer() || version->get<int>() < 1 ||
        version->get<int>() > kStackFormatVersion) {
      fail("{}: version: unsupported value {} (this build reads 1..{})", path.string(),
           printable(version->dump()), kStackFormatVersion);
    }
  }
  return manifest;
}

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
                   {"width", files.size.width},
                   {"height", files.size.height},
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

std::optional<cv::Size> manifest_image_size(const std::filesystem::path& path, const json& manifest) {
  const auto width = manifest.find("width");
  const auto height = manifest.find("height");
  if (width == manifest.end() || height == manifest.end()) return std::nullopt;
  for (const auto& [key, value] : {std::pair{"width", width}, std::pair{"height", height}}) {
    if (!value->is_number_integer() || value->get<std::int64_t>() <= 0 ||
        value->get<std::int64_t>() > 1 << 30) {
      fail("{}: {}: expected a positive image size, got {}", path.string(), key, printable(value->dump()));
    }
  }
  return cv::Size(width->get<int>(), height->get<int>());
}

void apply_manifest(const std::filesystem::path& path, ImageStack& stack) {
  apply_manifest(path, read_manifest_json(path), stack);
}

void apply_manifest(const std::filesystem::path& path, const json& manifest, ImageStack& stack) {
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
        fail("{}: frames[{}].file: {} does not match '{}' from filenames.txt", path.string(), i,
             printable(file->dump()), printable(frame.filename));
      }
    }
    read_frame_fields(entry, frame, path, i);
  }
}

CaptureManifest read_capture_manifest(const std::filesystem::path& path) {
  const json manifest = read_manifest_json(path);
  const auto section = manifest.find("capture");
  if (section == manifest.end() || !section->is_object())
    fail("{}: not a capture (no 'capture' object)", path.string());
  const json& c = *section;
  const auto field = [&](const char* key) -> const json& {
    const auto it = c.find(key);
    if (it == c.end()) fail("{}: capture.{}: missing", path.string(), key);
    return *it;
  };
  const auto version = c.find("version");
  if (version == c.end() || !version->is_number_integer() || version->get<int>() != kCaptureFormatVersion) {
    fail("{}: capture.version {} is not {}", path.string(),
         version == c.end() ? "(missing)" : printable(version->dump()), kCaptureFormatVersion);
  }
  CaptureManifest out;
  const json& plan = field("plan_led_ids");
  if (!plan.is_array()) fail("{}: capture.plan_led_ids: expected an array of LED ids", path.string());
  for (std::size_t k = 0; k < plan.size(); ++k)
    out.plan_led_ids.push_back(integer_field(plan[k], fmt::format("capture.plan_led_ids[{}]", k), path));
  const json& done = field("done");
  if (!done.is_array()) fail("{}: capture.done: expected an array of frame indices", path.string());
  for (std::size_t k = 0; k < done.size(); ++k) {
    const int index = integer_field(done[k], fmt::format("capture.done[{}]", k), path);
    if (index < 0) fail("{}: capture.done[{}]: negative index {}", path.string(), k, index);
    out.done.push_back(static_cast<std::size_t>(index));
  }
  const json& exposures = field("exposure_us");
  if (!exposures.is_object())
    fail("{}: capture.exposure_us: expected an object of LED id -> us", path.string());
  for (const auto& [id, e] : exposures.items()) {
    const std::string name = fmt::format("capture.exposure_us.{}", id);
    out.exposure_us[led_id_key(id, name, path)] = number_value(e, name, path);
  }
  if (const auto stops = c.find("bracket_stops"); stops != c.end())
    out.bracket_stops = numbers_field(*stops, "capture.bracket_stops", path);
  if (const auto brackets = c.find("bracket_exposure_us"); brackets != c.end()) {
    if (!brackets->is_object())
      fail("{}: capture.bracket_exposure_us: expected an object of LED id -> [us]", path.string());
    for (const auto& [id, list] : brackets->items()) {
      const std::string name = fmt::format("capture.bracket_exposure_us.{}", id);
      out.bracket_exposure_us[led_id_key(id, name, path)] = numbers_field(list, name, path);
    }
  }
  if (const auto count = c.find("dark_frames"); count != c.end())
    out.dark_frames = integer_field(*count, "capture.dark_frames", path);
  if (const auto fixed = c.find("fixed_exposure_us"); fixed != c.end()) {
    out.fixed_exposure = !fixed->is_null();
    if (!fixed->is_null()) out.fixed_exposure_us = number_value(*fixed, "capture.fixed_exposure_us", path);
  }
  const json& darks = field("darks");
  if (!darks.is_object()) fail("{}: capture.darks: expected an object", path.string());
  for (const auto& [key, d] : darks.items()) {
    const std::string name = fmt::format("capture.darks.{}", key);
    if (!d.is_object()) fail("{}: {}: expected an object", path.string(), name);
    CaptureDark dark;
    const auto file = d.find("file");
    if (file == d.end()) fail("{}: {}.file: missing", path.string(), name);
    dark.file = folder_file(*file, name + ".file", path);
    const auto mean = d.find("mean");
    if (mean == d.end()) fail("{}: {}.mean: missing", path.string(), name);
    dark.mean = number_value(*mean, name + ".mean", path);
    // The exact exposure (the key is rounded to whole microseconds).
    if (const auto e = d.find("exposure_us"); e != d.end()) {
      dark.exposure_us = number_value(*e, name + ".exposure_us", path);
    } else {
      dark.exposure_us = number_key(key, name, path);
    }
    out.darks.push_back(std::move(dark));
  }
  const auto frames = manifest.find("frames");
  if (frames == manifest.end()) return out;
  if (!frames->is_array()) fail("{}: frames: expected an array, got {}", path.string(), frames->type_name());
  for (std::size_t i = 0; i < frames->size(); ++i) {
    const json& entry = (*frames)[i];
    if (!entry.is_object())
      fail("{}: frames[{}]: expected an object, got {}", path.string(), i, entry.type_name());
    ManifestFrame listed;
    Frame& frame = listed.frame;
    const auto required = [&](const char* key) -> const json& {
      const auto it = entry.find(key);
      if (it == entry.end()) fail("{}: frames[{}].{}: missing", path.string(), i, key);
      return *it;
    };
    frame.filename = folder_file(required("file"), fmt::format("frames[{}].file", i), path);
    frame.led_id = integer_field(required("led_id"), fmt::format("frames[{}].led_id", i), path);
    frame.light_direction =
        vec3_field(required("light_direction"), fmt::format("frames[{}].light_direction", i), path);
    frame.light_intensity =
        vec3_field(required("light_intensity"), fmt::format("frames[{}].light_intensity", i), path);
    read_frame_fields(entry, frame, path, i);
    for (const auto& [key, value] : entry.items()) {
      if (std::ranges::find(kFrameKeys, key) == std::end(kFrameKeys)) listed.extra[key] = value;
    }
    out.frames.push_back(std::move(listed));
  }
  return out;
}

}  // namespace lightstage::io
