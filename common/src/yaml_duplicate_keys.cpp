#include "yaml_duplicate_keys.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/printable.hpp"

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/mark.h>
#include <yaml-cpp/parser.h>

#include <map>
#include <sstream>
#include <vector>

namespace lightstage {
namespace {

class DuplicateKeyFinder : public YAML::EventHandler {
 public:
  explicit DuplicateKeyFinder(std::string source) : source_(std::move(source)) {}

  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override { node_done(); }
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override { node_done(); }
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                const std::string& value) override {
    if (!levels_.empty() && levels_.back().is_map && levels_.back().at_key) key(mark, value);
    node_done();
  }
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {
    levels_.push_back(Level{false, true, {}, child_path(), {}, 0});
  }
  void OnSequenceEnd() override { close(); }
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    levels_.push_back(Level{true, true, {}, child_path(), {}, 0});
  }
  void OnMapEnd() override { close(); }

 private:
  struct Level {
    bool is_map = false;
    bool at_key = true;                // a mapping: the next node is a key
    std::map<std::string, int> lines;  // a mapping: key -> 1-based line
    std::string path;                  // of this node, as YamlField names fields
    std::string key;                   // a mapping: the key whose value comes next
    std::size_t index = 0;             // a list: the next element's index
  };

  void key(const YAML::Mark& mark, const std::string& name) {
    Level& level = levels_.back();
    const int line = mark.line + 1;
    const auto [it, fresh] = level.lines.emplace(name, line);
    if (!fresh) {
      const std::string path = level.path.empty() ? name : level.path + "." + name;
      fail("{}:{}: duplicate key '{}' (first at line {})", source_, line, printable(path), it->second);
    }
    level.key = name;
  }

  std::string child_path() const {
    if (levels_.empty()) return "";
    const Level& parent = levels_.back();
    if (!parent.is_map) return parent.path + "[" + std::to_string(parent.index) + "]";
    if (parent.at_key) return parent.path;  // a complex key: only its own keys are checked
    return parent.path.empty() ? parent.key : parent.path + "." + parent.key;
  }

  void close() {
    levels_.pop_back();
    node_done();
  }

  void node_done() {
    if (levels_.empty()) return;
    Level& parent = levels_.back();
    if (parent.is_map) {
      parent.at_key = !parent.at_key;
    } else {
      ++parent.index;
    }
  }

  std::string source_;
  std::vector<Level> levels_;
};

}  // namespace

void refuse_duplicate_yaml_keys(const std::string& yaml_text, const std::string& source) {
  std::istringstream in(yaml_text);
  YAML::Parser parser(in);
  DuplicateKeyFinder finder(source);
  parser.HandleNextDocument(finder);
}

}  // namespace lightstage
