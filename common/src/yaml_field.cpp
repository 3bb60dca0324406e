#include "lightstage/common/yaml_field.hpp"

#include "lightstage/common/printable.hpp"
#include "yaml_duplicate_keys.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

namespace lightstage {

void YamlField::error(const std::string& what) const {
  const int line = node_.Mark().line >= 0 ? node_.Mark().line + 1 : 0;
  const std::string field = path_.empty() ? std::string() : "field '" + printable(path_) + "': ";
  if (line > 0) fail("{}:{}: {}{}", source_, line, field, what);
  fail("{}: {}{}", source_, field, what);
}

YamlField YamlField::operator[](const std::string& key) const {
  if (!node_.IsMap()) error("expected a mapping");
  YAML::Node child = node_[key];
  if (!child.IsDefined()) error("missing key '" + key + "'");
  return YamlField(child, source_, path_.empty() ? key : path_ + "." + key);
}

YamlField YamlField::at(std::size_t i) const {
  return YamlField(node_[i], source_, path_ + "[" + std::to_string(i) + "]");
}

std::size_t YamlField::size() const {
  if (!node_.IsSequence()) error("expected a list");
  return node_.size();
}

void YamlField::only_keys(const std::set<std::string>& allowed) const {
  if (!node_.IsMap()) error("expected a mapping");
  for (const auto& kv : node_) {
    if (!kv.first.IsScalar()) YamlField(kv.first, source_, path_).error("keys must be plain names");
    const std::string& key = kv.first.Scalar();
    if (!allowed.contains(key)) {
      YamlField(kv.first, source_, path_.empty() ? key : path_ + "." + key).error("unknown key");
    }
  }
}

std::string YamlField::text() const {
  if (!node_.IsScalar()) error("expected a value");
  return node_.Scalar();
}

double YamlField::number() const {
  if (!node_.IsScalar()) error("expected a number");
  double value = 0;
  try {
    value = node_.as<double>();
  } catch (const YAML::Exception&) {
    error("cannot read '" + printable(node_.Scalar()) + "' as a number");
  }
  if (!std::isfinite(value)) error("must be a finite number");
  return value;
}

double YamlField::positive() const {
  const double value = number();
  if (value <= 0) error("must be positive, got " + printable(node_.Scalar()));
  return value;
}

double YamlField::non_negative() const {
  const double value = number();
  if (value < 0) error("must not be negative, got " + printable(node_.Scalar()));
  return value;
}

int YamlField::integer() const {
  if (!node_.IsScalar()) error("expected an integer");
  try {
    return node_.as<int>();
  } catch (const YAML::Exception&) {
    error("cannot read '" + printable(node_.Scalar()) + "' as an integer");
  }
}

bool YamlField::boolean() const {
  if (!node_.IsScalar()) error("expected true or false");
  try {
    return node_.as<bool>();
  } catch (const YAML::Exception&) {
    error("cannot read '" + printable(node_.Scalar()) + "' as true/false");
  }
}

Vec2 YamlField::vec2() const {
  if (!node_.IsSequence() || node_.size() != 2) error("expected [x, y]");
  return {at(0).number(), at(1).number()};
}

Vec3 YamlField::vec3() const {
  if (!node_.IsSequence() || node_.size() != 3) error("expected [x, y, z]");
  return {at(0).number(), at(1).number(), at(2).number()};
}

YAML::Node load_yaml(const std::string& yaml_text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::ParserException& e) {
    fail("{}:{}: not valid YAML: {}", source, e.mark.line + 1, e.msg);
  }
  refuse_duplicate_yaml_keys(yaml_text, source);
  return root;
}

std::string read_text_file(const std::filesystem::path& path, const std::string& what) {
  std::ifstream in(path);
  if (!in) fail("{}: cannot open {}", path.string(), what);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace lightstage
