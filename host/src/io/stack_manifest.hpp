#pragma once
// manifest.json of a stack folder: building it when writing, applying it to
// loaded frames when reading. The keys are documented in docs/stack-format.md.

#include "lightstage/common/image_stack.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace lightstage::io {

inline constexpr const char* kStackFormat = "lightstage-stack";
inline constexpr int kStackFormatVersion = 1;

// File names of the optional parts actually written (empty = not written).
struct StackFiles {
  std::vector<std::string> frames;
  std::string mask;
  std::string normals;
  std::string depth;
};

// The manifest for `stack` written as `files`, merged with `extra` (see write_stack).
// Throws InputError when `extra` is not an object or collides with a reserved key.
nlohmann::json build_manifest(const ImageStack& stack, const StackFiles& files, const nlohmann::json& extra);

// Reads `path` and fills each frame's led_id, led_position_mm, exposure_us,
// gain, black_level, saturation_level and dark_file (the images themselves are
// loaded by load_stack). Throws InputError naming the file
// and the field for bad JSON, a wrong format or version, a frame count or
// file name that disagrees with filenames.txt, or a value of the wrong type.
void apply_manifest(const std::filesystem::path& path, ImageStack& stack);

}  // namespace lightstage::io
