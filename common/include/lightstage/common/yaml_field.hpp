#pragma once
// A YAML node together with where it came from, so that every error in a
// YAML file (rigs, scenes) names the file, the line and the field's path:
//     hw/rigs/x.yaml:37: field 'leds[12].limits.max_duty': must be in (0, 1]
// Used by the parsers of outside YAML; every failure is an InputError.

#include "lightstage/common/error.hpp"
#include "lightstage/common/geometry.hpp"

#include <yaml-cpp/yaml.h>

#include <cstddef>
#include <filesystem>
#include <set>
#include <string>

namespace lightstage {

class YamlField {
 public:
  YamlField(YAML::Node node, std::string source, std::string path)
      : node_(std::move(node)), source_(std::move(source)), path_(std::move(path)) {}

  [[noreturn]] void error(const std::string& what) const;

  bool has(const std::string& key) const { return node_.IsMap() && node_[key].IsDefined(); }
  bool is_map() const { return node_.IsMap(); }
  bool is_scalar() const { return node_.IsScalar(); }
  const std::string& path() const { return path_; }

  YamlField operator[](const std::string& key) const;  // a required key
  YamlField at(std::size_t i) const;                   // a list element
  std::size_t size() const;                            // of a list

  // Rejects keys outside `allowed`: a misspelt limit must not be silently ignored.
  void only_keys(const std::set<std::string>& allowed) const;

  std::string text() const;
  double number() const;  // finite
  double positive() const;
  double non_negative() const;
  int integer() const;
  bool boolean() const;
  Vec2 vec2() const;  // [x, y]
  Vec3 vec3() const;  // [x, y, z]

 private:
  YAML::Node node_;
  std::string source_;
  std::string path_;
};

// Parses YAML text; syntax errors become InputErrors naming `source` and the line.
YAML::Node load_yaml(const std::string& yaml_text, const std::string& source);

// Parses `yaml_text` and hands the root to `parse`. Anything yaml-cpp still
// throws (a structure no check anticipated) becomes an InputError with its line.
template <typename Parse>
auto parse_yaml(const std::string& yaml_text, const std::string& source, Parse&& parse) {
  const YAML::Node root = load_yaml(yaml_text, source);
  try {
    return parse(YamlField(root, source, ""));
  } catch (const YAML::Exception& e) {
    fail("{}:{}: {}", source, e.mark.line + 1, e.msg);
  }
}

// Reads a whole text file; a missing or unreadable file is an InputError naming `what` and the path.
std::string read_text_file(const std::filesystem::path& path, const std::string& what);

}  // namespace lightstage
