#include "lightstage/common/rig.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/printable.hpp"

#include "lightstage/common/yaml_field.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace lightstage {
namespace {

using Field = YamlField;

// A duration in microseconds: positive and at most kMaxRigDurationUs, so that
// the firmware's nanosecond clocks (int64) cannot overflow whatever the file says.
// `may_be_zero`: for a delay that a rig may not have at all (a lag, a lead).
double duration_us(const Field& f, bool may_be_zero = false) {
  const double value = may_be_zero ? f.non_negative() : f.positive();
  if (value > kMaxRigDurationUs) {
    f.error(
        fmt::format("must be at most {:.0f} us (one hour), got {}", kMaxRigDurationUs, printable(f.text())));
  }
  return value;
}

// A line: an offset ("7"), a name ("LED_07"), or {line: ..., active_low: true}.
LineRef parse_line(const Field& f) {
  LineRef ref;
  if (f.is_map()) {
    f.only_keys({"line", "active_low"});
    ref = parse_line(f["line"]);
    if (f.has("active_low")) ref.active_low = f["active_low"].boolean();
    return ref;
  }
  const std::string text = f.text();
  char* end = nullptr;
  const long offset = std::strtol(text.c_str(), &end, 10);
  if (!text.empty() && end && *end == '\0') {
    if (offset < 0 || offset > 4095) f.error("line offset out of range: " + text);
    ref.offset = static_cast<int>(offset);
  } else {
    ref.name = text;
  }
  return ref;
}

LedLimits parse_limits(const Field& f, LedLimits limits) {
  f.only_keys({"max_on_us", "max_duty", "duty_window_us"});
  if (f.has("max_on_us")) limits.max_on_us = duration_us(f["max_on_us"]);
  if (f.has("max_duty")) {
    limits.max_duty = f["max_duty"].positive();
    if (limits.max_duty > 1) f["max_duty"].error("must be in (0, 1]");
  }
  if (f.has("duty_window_us")) limits.duty_window_us = duration_us(f["duty_window_us"]);
  return limits;
}

CameraDefaults parse_camera(const Field& f) {
  f.only_keys({"model", "width", "height", "pixel_pitch_mm", "focal_px", "position_mm", "exposure_us", "gain",
               "bit_depth", "uri"});
  CameraDefaults cam;
  if (f.has("model")) {
    const auto model = f["model"].text();
    if (model == "orthographic") {
      cam.model = CameraModel::kOrthographic;
    } else if (model == "pinhole") {
      cam.model = CameraModel::kPinhole;
    } else {
      f["model"].error("must be 'orthographic' or 'pinhole', got '" + printable(model) + "'");
    }
  }
  cam.width = f["width"].integer();
  cam.height = f["height"].integer();
  if (cam.width <= 0 || cam.width > 16384) f["width"].error("must be in 1..16384");
  if (cam.height <= 0 || cam.height > 16384) f["height"].error("must be in 1..16384");
  if (f.has("pixel_pitch_mm")) cam.pixel_pitch_mm = f["pixel_pitch_mm"].positive();
  if (f.has("focal_px")) cam.focal_px = f["focal_px"].positive();
  if (f.has("position_mm")) cam.position_mm = f["position_mm"].vec3();
  if (cam.model == CameraModel::kPinhole && cam.focal_px <= 0) {
    f.error("a pinhole camera needs focal_px");
  }
  if (f.has("exposure_us")) cam.exposure_us = duration_us(f["exposure_us"]);
  if (f.has("gain")) cam.gain = f["gain"].positive();
  if (f.has("bit_depth")) {
    cam.bit_depth = f["bit_depth"].integer();
    if (cam.bit_depth < 8 || cam.bit_depth > 16) f["bit_depth"].error("must be in 8..16");
  }
  if (f.has("uri")) cam.uri = f["uri"].text();
  return cam;
}

ShiftRegisterChain parse_chain(const Field& f) {
  f.only_keys({"name", "data", "clock", "latch", "output_enable", "length", "clock_period_us"});
  ShiftRegisterChain chain;
  chain.name = f["name"].text();
  chain.data = parse_line(f["data"]);
  chain.clock = parse_line(f["clock"]);
  chain.latch = parse_line(f["latch"]);
  if (f.has("output_enable")) chain.output_enable = parse_line(f["output_enable"]);
  chain.length = f["length"].integer();
  if (chain.length <= 0 || chain.length > 4096) f["length"].error("must be in 1..4096");
  if (f.has("clock_period_us")) chain.clock_period_us = duration_us(f["clock_period_us"]);
  return chain;
}

Led parse_led(const Field& f, const LedLimits& default_limits, const std::string& default_colour) {
  f.only_keys({"id", "position_mm", "line", "chain", "bit", "colour", "wavelength_nm", "relative_intensity",
               "limits"});
  Led led;
  led.id = f["id"].integer();
  if (led.id < 0) f["id"].error("must not be negative");
  led.position_mm = f["position_mm"].vec3();
  if (f.has("line") == f.has("chain")) {
    f.error("an LED is wired either to a 'line' or to a 'chain' bit, exactly one");
  }
  if (f.has("line")) {
    led.wiring = DirectWiring{parse_line(f["line"])};
  } else {
    led.wiring = ChainWiring{f["chain"].text(), f["bit"].integer()};
  }
  led.colour = f.has("colour") ? f["colour"].text() : default_colour;
  if (f.has("wavelength_nm")) led.wavelength_nm = f["wavelength_nm"].positive();
  if (f.has("relative_intensity")) led.relative_intensity = f["relative_intensity"].positive();
  led.limits = f.has("limits") ? parse_limits(f["limits"], default_limits) : default_limits;
  return led;
}

// Checks that span several fields: ids, wiring collisions, chain bits, limits.
void check_rig(const Rig& rig, const Field& root) {
  std::map<std::string, std::string> line_users;  // line key -> what uses it
  auto claim = [&](const LineRef& line, const std::string& user, const Field& where) {
    const std::string key = line.by_name() ? "name:" + line.name : "offset:" + std::to_string(line.offset);
    const auto [it, fresh] = line_users.emplace(key, user);
    if (!fresh) where.error(line.describe() + " is already used by " + it->second);
  };
  claim(rig.trigger.line, "the camera trigger", root["trigger"]);
  if (rig.trigger.focus)
    claim(rig.trigger.focus->line, "the camera's focus (half-press)", root["trigger"]["focus"]);
  if (rig.strobe) claim(rig.strobe->line, "the strobe input", root["strobe"]);
  for (std::size_t i = 0; i < rig.chains.size(); ++i) {
    const auto& c = rig.chains[i];
    const Field where = root["chains"].at(i);
    claim(c.data, "chain '" + c.name + "' data", where);
    claim(c.clock, "chain '" + c.name + "' clock", where);
    claim(c.latch, "chain '" + c.name + "' latch", where);
    if (c.output_enable) claim(*c.output_enable, "chain '" + c.name + "' output enable", where);
    for (std::size_t j = 0; j < i; ++j) {
      if (rig.chains[j].name == c.name)
        where["name"].error("duplicate chain name '" + printable(c.name) + "'");
    }
  }
  std::set<int> ids;
  std::set<std::pair<std::string, int>> chain_bits;
  for (std::size_t i = 0; i < rig.leds.size(); ++i) {
    const Led& led = rig.leds[i];
    const Field where = root["leds"].at(i);
    if (!ids.insert(led.id).second) where["id"].error("duplicate LED id " + std::to_string(led.id));
    if (led.limits.max_on_us <= 0) where.error("no max_on_us limit (set it here or in led_defaults.limits)");
    if (led.limits.max_duty <= 0) where.error("no max_duty limit (set it here or in led_defaults.limits)");
    if ((led.position_mm - rig.object_position_mm).norm() < 1e-6) {
      where["position_mm"].error("LED sits on the object position");
    }
    if (const auto* direct = std::get_if<DirectWiring>(&led.wiring)) {
      claim(direct->line, "LED " + std::to_string(led.id), where["line"]);
    } else {
      const auto& bit = std::get<ChainWiring>(led.wiring);
      const ShiftRegisterChain* chain = rig.chain(bit.chain);
      if (!chain) where["chain"].error("no chain named '" + printable(bit.chain) + "'");
      if (bit.bit < 0 || bit.bit >= chain->length) {
        where["bit"].error("bit " + std::to_string(bit.bit) + " outside chain '" + bit.chain +
                           "' of length " + std::to_string(chain->length));
      }
      if (!chain_bits.emplace(bit.chain, bit.bit).second) {
        where["bit"].error("bit " + std::to_string(bit.bit) + " of chain '" + bit.chain +
                           "' is already used by another LED");
      }
    }
  }
}

Rig parse_document(const Field& root, const std::string& source) {
  if (!root.is_map()) root.error("a rig file is a YAML mapping");
  root.only_keys({"name", "description", "dome_radius_mm", "object_position_mm", "camera", "trigger",
                  "strobe", "chains", "led_defaults", "leds"});
  Rig rig;
  rig.source = source;
  rig.name = root["name"].text();
  if (rig.name.empty()) root["name"].error("must not be empty");
  // The name is printed by both sides and compared between them: no terminal controls in it.
  if (std::any_of(rig.name.begin(), rig.name.end(), [](unsigned char c) { return c < 0x20 || c == 0x7f; })) {
    root["name"].error("must not contain control characters, got '" + printable(rig.name) + "'");
  }
  if (root.has("description")) rig.description = root["description"].text();
  rig.dome_radius_mm = root["dome_radius_mm"].positive();
  if (root.has("object_position_mm")) rig.object_position_mm = root["object_position_mm"].vec3();
  rig.camera = parse_camera(root["camera"]);

  const Field trigger = root["trigger"];
  trigger.only_keys({"line", "active_low", "pulse_us", "focus", "shutter_lag_us", "arrival_timeout_us"});
  rig.trigger.line = parse_line(trigger["line"]);
  if (trigger.has("active_low")) rig.trigger.line.active_low = trigger["active_low"].boolean();
  if (trigger.has("pulse_us")) rig.trigger.pulse_us = duration_us(trigger["pulse_us"]);
  if (trigger.has("focus")) {
    const Field focus = trigger["focus"];
    focus.only_keys({"line", "active_low", "lead_us"});
    FocusLine f;
    f.line = parse_line(focus["line"]);
    if (focus.has("active_low")) f.line.active_low = focus["active_low"].boolean();
    if (focus.has("lead_us")) f.lead_us = duration_us(focus["lead_us"], true);
    rig.trigger.focus = f;
  }
  if (trigger.has("shutter_lag_us"))
    rig.trigger.shutter_lag_us = duration_us(trigger["shutter_lag_us"], true);
  if (trigger.has("arrival_timeout_us"))
    rig.trigger.arrival_timeout_us = duration_us(trigger["arrival_timeout_us"], true);

  if (root.has("strobe")) {
    const Field strobe = root["strobe"];
    strobe.only_keys({"line", "active_low", "timeout_us"});
    StrobeLine s;
    s.line = parse_line(strobe["line"]);
    if (strobe.has("active_low")) s.line.active_low = strobe["active_low"].boolean();
    if (strobe.has("timeout_us")) s.timeout_us = duration_us(strobe["timeout_us"]);
    rig.strobe = s;
  }

  if (root.has("chains")) {
    const Field chains = root["chains"];
    for (std::size_t i = 0; i < chains.size(); ++i) rig.chains.push_back(parse_chain(chains.at(i)));
  }

  LedLimits default_limits;
  std::string default_colour = "white";
  if (root.has("led_defaults")) {
    const Field defaults = root["led_defaults"];
    defaults.only_keys({"limits", "colour"});
    if (defaults.has("limits")) default_limits = parse_limits(defaults["limits"], default_limits);
    if (defaults.has("colour")) default_colour = defaults["colour"].text();
  }

  const Field leds = root["leds"];
  if (leds.size() == 0) leds.error("a rig needs at least one LED");
  for (std::size_t i = 0; i < leds.size(); ++i) {
    rig.leds.push_back(parse_led(leds.at(i), default_limits, default_colour));
  }
  check_rig(rig, root);
  return rig;
}

}  // namespace

std::string LineRef::describe() const {
  return by_name() ? "line \"" + printable(name) + "\"" : "line " + std::to_string(offset);
}

const Led& Rig::led(int id) const {
  for (const auto& led : leds) {
    if (led.id == id) return led;
  }
  fail("{}: no LED with id {}", source.string(), id);
}

const ShiftRegisterChain* Rig::chain(const std::string& chain_name) const {
  for (const auto& c : chains) {
    if (c.name == chain_name) return &c;
  }
  return nullptr;
}

Rig parse_rig(const std::string& yaml_text, const std::string& source) {
  return parse_yaml(yaml_text, source, [&](const YamlField& root) { return parse_document(root, source); });
}

Rig load_rig(const std::filesystem::path& path) {
  return parse_rig(read_text_file(path, "rig file"), path.string());
}

std::filesystem::path rig_directory() {
  if (const char* dir = std::getenv("LIGHTSTAGE_RIG_DIR")) return dir;
  for (const std::filesystem::path& candidate : {std::filesystem::path(LIGHTSTAGE_SOURCE_RIG_DIR),
                                                 std::filesystem::path(LIGHTSTAGE_INSTALL_RIG_DIR)}) {
    if (std::filesystem::exists(candidate / "sim-dome.yaml")) return candidate;
  }
  return LIGHTSTAGE_SOURCE_RIG_DIR;
}

std::filesystem::path default_rig_path() { return rig_directory() / "sim-dome.yaml"; }

}  // namespace lightstage
