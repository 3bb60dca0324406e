#pragma once
// Scenes from YAML (every key documented in docs/scene-format.md) and the
// named presets, which are themselves YAML texts parsed by the same code.

#include "lightstage/sim/scene.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace lightstage::sim {

// Parses scene YAML; `source` names it in messages ("file:line: field 'x': ...").
Scene parse_scene(const std::string& yaml_text, const std::string& source);
Scene load_scene(const std::filesystem::path& path);

// A colour spec, the value of a scene's `colour` key as YAML text
// (docs/scene-format.md): "0.9,0.6,0.3", "[0.9, 0.6, 0.3]", "patches",
// "checker", "{type: patches, period_mm: 16, saturation: 0.6, seed: 3}",
// "{type: checker, values: [[0.9, 0.3, 0.3], [0.3, 0.3, 0.9]], period_mm: 10}".
// Throws InputError naming the spec, the key and the value.
ColourTexture parse_colour(const std::string& spec);

// The preset names ("sphere", "chrome-sphere", ...), for --help.
std::vector<std::string> scene_presets();
// The YAML text of a preset; throws InputError for an unknown name.
std::string scene_preset_yaml(const std::string& name);

// A preset name, else a path to a scene file.
Scene resolve_scene(const std::string& name_or_path);

}  // namespace lightstage::sim
