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

// The preset names ("sphere", "chrome-sphere", ...), for --help.
std::vector<std::string> scene_presets();
// The YAML text of a preset; throws InputError for an unknown name.
std::string scene_preset_yaml(const std::string& name);

// A preset name, else a path to a scene file.
Scene resolve_scene(const std::string& name_or_path);

}  // namespace lightstage::sim
