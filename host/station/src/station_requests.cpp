#include "lightstage/station/station_requests.hpp"

#include "lightstage/station/operator_access.hpp"

#include <fmt/format.h>

#include <cmath>
#include <set>

namespace lightstage::station {
namespace {

[[noreturn]] void bad(const std::string& message) { throw Refused(400, message); }

// The body must be an object holding only `known` fields.
void only_fields(const nlohmann::json& body, const std::set<std::string>& known, const char* what) {
  if (!body.is_object()) bad(fmt::format("{}: the body must be a JSON object", what));
  for (const auto& [key, value] : body.items()) {
    if (!known.count(key)) bad(fmt::format("{}: unknown field '{}'", what, key));
  }
}

double number(const nlohmann::json& value, const std::string& field, double low, double high) {
  if (!value.is_number()) bad(fmt::format("{}: must be a number", field));
  const double x = value.get<double>();
  if (!std::isfinite(x) || x < low || x > high)
    bad(fmt::format("{}: {} is not in [{}, {}]", field, x, low, high));
  return x;
}

int integer(const nlohmann::json& value, const std::string& field, int low, int high) {
  if (!value.is_number_integer()) bad(fmt::format("{}: must be an integer", field));
  const auto x = value.get<std::int64_t>();
  if (x < low || x > high) bad(fmt::format("{}: {} is not in [{}, {}]", field, x, low, high));
  return static_cast<int>(x);
}

std::string text(const nlohmann::json& value, const std::string& field) {
  if (!value.is_string()) bad(fmt::format("{}: must be a string", field));
  return value.get<std::string>();
}

const nlohmann::json& array(const nlohmann::json& value, const std::string& field, std::size_t max_size) {
  if (!value.is_array()) bad(fmt::format("{}: must be an array", field));
  if (value.size() > max_size) bad(fmt::format("{}: more than {} entries", field, max_size));
  return value;
}

constexpr int kMaxLeds = 100000;
constexpr double kMaxExposureUs = 60e6;

}  // namespace

void check_folder_name(const std::string& name, const std::string& field) {
  if (name.empty() || name.size() > 64) bad(fmt::format("{}: a name of 1 to 64 characters is needed", field));
  if (name.front() == '.') bad(fmt::format("{}: '{}' must not start with '.'", field, name));
  for (const char c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
                    c == '_' || c == '-';
    if (!ok) bad(fmt::format("{}: '{}' may hold only letters, digits, '.', '_' and '-'", field, name));
  }
}

LedsRequest leds_request(const nlohmann::json& body) {
  only_fields(body, {"leds"}, "leds");
  if (!body.contains("leds")) bad("leds: missing field 'leds' (a list of {id, level}; [] = dark)");
  LedsRequest request;
  std::set<std::uint32_t> seen;
  for (const auto& led : array(body["leds"], "leds", kMaxLeds)) {
    only_fields(led, {"id", "level"}, "leds[]");
    if (!led.contains("id")) bad("leds[]: missing field 'id'");
    const auto id = static_cast<std::uint32_t>(integer(led["id"], "leds[].id", 0, kMaxLeds));
    const float level =
        led.contains("level") ? static_cast<float>(number(led["level"], "leds[].level", 0, 1)) : 1.0f;
    if (!seen.insert(id).second) bad(fmt::format("leds: LED {} given twice", id));
    if (level > 0) request.levels.emplace_back(id, level);
  }
  return request;
}

PreviewRequest preview_request(const nlohmann::json& body) {
  only_fields(body, {"led", "exposure_us", "gain"}, "preview");
  if (!body.contains("led") || !body.contains("exposure_us"))
    bad("preview: the fields 'led' and 'exposure_us' are needed");
  PreviewRequest request;
  request.led = static_cast<std::uint32_t>(integer(body["led"], "preview.led", 0, kMaxLeds));
  request.exposure_us = number(body["exposure_us"], "preview.exposure_us", 1, kMaxExposureUs);
  if (body.contains("gain")) request.gain = number(body["gain"], "preview.gain", 0, 1e6);
  return request;
}

TestSequenceRequest test_sequence_request(const nlohmann::json& body) {
  only_fields(body, {"on_us"}, "test-sequence");
  TestSequenceRequest request;
  if (body.contains("on_us"))
    request.on_us = static_cast<std::uint32_t>(integer(body["on_us"], "test-sequence.on_us", 100, 2'000'000));
  return request;
}

CaptureRequest capture_request(const nlohmann::json& body) {
  only_fields(body, {"name", "target", "exposure_us", "dark_frames", "bracket_stops", "led_ids"}, "capture");
  if (!body.contains("name")) bad("capture: missing field 'name' (the stack's folder name)");
  CaptureRequest request;
  request.name = text(body["name"], "capture.name");
  check_folder_name(request.name, "capture.name");
  if (body.contains("exposure_us") && !(body["exposure_us"].is_string() && body["exposure_us"] == "auto"))
    request.exposure_us = number(body["exposure_us"], "capture.exposure_us", 1, kMaxExposureUs);
  if (body.contains("target")) {
    const std::string target = text(body["target"], "capture.target");
    if (target != "object" && target != "chrome-sphere")
      bad(fmt::format("capture.target: '{}' is neither object nor chrome-sphere", target));
    request.chrome_sphere = target == "chrome-sphere";
  }
  if (body.contains("dark_frames"))
    request.dark_frames = integer(body["dark_frames"], "capture.dark_frames", 0, 64);
  if (body.contains("bracket_stops")) {
    for (const auto& stop : array(body["bracket_stops"], "capture.bracket_stops", 8))
      request.bracket_stops.push_back(number(stop, "capture.bracket_stops[]", -16, 16));
  }
  if (body.contains("led_ids")) {
    for (const auto& id : array(body["led_ids"], "capture.led_ids", kMaxLeds))
      request.led_ids.push_back(integer(id, "capture.led_ids[]", 0, kMaxLeds));
  }
  return request;
}

CalibrationRequest calibration_request(const nlohmann::json& body) {
  only_fields(body, {"name", "stacks", "allow_missing"}, "calibration");
  if (!body.contains("name") || !body.contains("stacks"))
    bad("calibration: the fields 'name' and 'stacks' (the chrome-sphere captures) are needed");
  CalibrationRequest request;
  request.name = text(body["name"], "calibration.name");
  check_folder_name(request.name, "calibration.name");
  for (const auto& stack : array(body["stacks"], "calibration.stacks", 16)) {
    request.stacks.push_back(text(stack, "calibration.stacks[]"));
    check_folder_name(request.stacks.back(), "calibration.stacks[]");
  }
  if (request.stacks.empty()) bad("calibration.stacks: at least one chrome-sphere capture is needed");
  if (body.contains("allow_missing")) {
    if (!body["allow_missing"].is_boolean()) bad("calibration.allow_missing: must be true or false");
    request.allow_missing = body["allow_missing"].get<bool>();
  }
  return request;
}

SphereCircle sphere_request(const nlohmann::json& body) {
  only_fields(body, {"x_px", "y_px", "radius_px"}, "sphere");
  if (!body.contains("x_px") || !body.contains("y_px") || !body.contains("radius_px"))
    bad("sphere: x_px, y_px and radius_px are needed");
  return {number(body["x_px"], "sphere.x_px", 0, 1e6), number(body["y_px"], "sphere.y_px", 0, 1e6),
          number(body["radius_px"], "sphere.radius_px", 2, 1e6)};
}

SolveRequest solve_request(const nlohmann::json& body) {
  only_fields(body, {"stack", "method", "calibration", "name"}, "solve");
  if (!body.contains("stack")) bad("solve: missing field 'stack'");
  SolveRequest request;
  request.stack = text(body["stack"], "solve.stack");
  check_folder_name(request.stack, "solve.stack");
  if (body.contains("method")) request.method = text(body["method"], "solve.method");
  if (body.contains("calibration") && !body["calibration"].is_null()) {
    request.calibration = text(body["calibration"], "solve.calibration");
    if (!request.calibration.empty()) check_folder_name(request.calibration, "solve.calibration");
  }
  if (body.contains("name")) request.name = text(body["name"], "solve.name");
  if (request.name.empty()) request.name = request.stack + "-" + request.method;
  check_folder_name(request.name, "solve.name");
  return request;
}

nlohmann::json CaptureRequest::to_json() const {
  nlohmann::json j = {{"name", name},
                      {"target", chrome_sphere ? "chrome-sphere" : "object"},
                      {"dark_frames", dark_frames},
                      {"bracket_stops", bracket_stops},
                      {"led_ids", led_ids}};
  j["exposure_us"] = exposure_us ? nlohmann::json(*exposure_us) : nlohmann::json("auto");
  return j;
}

nlohmann::json CalibrationRequest::to_json() const {
  return {{"name", name}, {"stacks", stacks}, {"allow_missing", allow_missing}};
}

nlohmann::json SolveRequest::to_json() const {
  return {{"stack", stack}, {"method", method}, {"calibration", calibration}, {"name", name}};
}

}  // namespace lightstage::station
