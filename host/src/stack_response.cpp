#include "lightstage/host/stack_response.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"

#include <opencv2/core.hpp>

#include <fstream>
#include <system_error>
#include <vector>

namespace fs = std::filesystem;

namespace lightstage {
namespace {

nlohmann::json read_manifest(const fs::path& file) {
  std::error_code error;
  if (!fs::exists(file, error)) return nlohmann::json::object();
  std::ifstream in(file);
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    fail("{}: not valid JSON: {}", file.string(), e.what());
  }
}

bool read_bool(const nlohmann::json& object, const char* key, const fs::path& file, bool fallback) {
  const auto it = object.find(key);
  if (it == object.end() || it->is_null()) return fallback;
  if (!it->is_boolean())
    fail("{}: radiometry.{}: expected true or false, got {}", file.string(), key, it->dump());
  return it->get<bool>();
}

// The response written inline: parsed through a file so one parser names the fields.
InverseResponse inline_response(const nlohmann::json& curve, const fs::path& manifest) {
  if (!curve.is_object() || !curve.contains("bits") || !curve["bits"].is_number_integer() ||
      !curve.contains("knots") || !curve["knots"].is_array())
    fail("{}: radiometry.response: expected a lightstage-response object with bits and knots",
         manifest.string());
  std::vector<double> knots;
  for (std::size_t i = 0; i < curve["knots"].size(); ++i) {
    if (!curve["knots"][i].is_number())
      fail("{}: radiometry.response.knots[{}]: expected a number", manifest.string(), i);
    knots.push_back(curve["knots"][i].get<double>());
  }
  try {
    return InverseResponse(curve["bits"].get<int>(), std::move(knots));
  } catch (const Error& e) {
    fail("{}: radiometry.response: {}", manifest.string(), e.what());
  }
}

cv::Mat linearise_channels(const InverseResponse& response, const cv::Mat& image) {
  std::vector<cv::Mat> channels;
  cv::split(image, channels);
  for (cv::Mat& c : channels) c = response.linearise(c);
  cv::Mat out;
  cv::merge(channels, out);
  return out;
}

}  // namespace

StackLinearity read_stack_linearity(const fs::path& stack_dir) {
  const fs::path file = stack_dir / "manifest.json";
  const nlohmann::json manifest = read_manifest(file);
  StackLinearity result;
  if (!manifest.is_object()) return result;
  // Simulated stacks record their sensor model under "simulation" (older ones at the top level).
  const auto simulation = manifest.find("simulation");
  const nlohmann::json& holder =
      simulation != manifest.end() && simulation->is_object() && simulation->contains("sensor") ? *simulation
                                                                                                : manifest;
  if (const auto sensor = holder.find("sensor"); sensor != holder.end() && sensor->is_object()) {
    if (const auto curve = sensor->find("response"); curve != sensor->end() && curve->is_string()) {
      result.sensor_response = curve->get<std::string>();
      result.linear = result.sensor_response == "identity" || result.sensor_response == "linear";
    }
  }
  const auto radiometry = manifest.find("radiometry");
  if (radiometry == manifest.end() || radiometry->is_null()) return result;
  if (!radiometry->is_object())
    fail("{}: radiometry: expected an object, got {}", file.string(), radiometry->dump());
  result.linearised_at_capture = read_bool(*radiometry, "response_applied", file, false);
  const auto curve = radiometry->find("response");
  if (curve != radiometry->end() && !curve->is_null() && !result.linearised_at_capture)
    result.response = inline_response(*curve, file);
  result.linear = read_bool(*radiometry, "linear", file, result.linearised_at_capture || !result.response);
  return result;
}

void apply_response(const InverseResponse& response, ImageStack& stack, const std::string& where) {
  for (Frame& frame : stack.frames) {
    const int depth = frame.image.depth();
    if (depth != CV_8U && depth != CV_16U)
      fail("{}: {}: frames are already float (linear); a camera response applies to 8- or 16-bit frames",
           where, frame.filename);
    const double full = depth == CV_8U ? 255.0 : 65535.0;
    // A response fitted on data of one bit depth reads a value by its share of full scale.
    const double to_response = static_cast<double>((1 << response.bits()) - 1) / full;
    const InverseResponse& curve = response;
    cv::Mat scaled = frame.image;
    if (std::abs(to_response - 1.0) > 1e-12) {
      frame.image.convertTo(scaled, response.bits() <= 8 ? CV_8U : CV_16U, to_response);
    }
    frame.image = linearise_channels(curve, scaled);
    if (!frame.dark.empty()) {
      cv::Mat dark = frame.dark;
      if (std::abs(to_response - 1.0) > 1e-12)
        frame.dark.convertTo(dark, response.bits() <= 8 ? CV_8U : CV_16U, to_response);
      frame.dark = linearise_channels(curve, dark);
    }
    frame.black_level = curve.at(frame.black_level * to_response);
    const double saturation = frame.saturation_level > 0 ? frame.saturation_level : full;
    frame.saturation_level = curve.at(saturation * to_response);
  }
}

StackResponse choose_stack_response(const fs::path& stack_dir, const fs::path& response_file) {
  const StackLinearity linearity = read_stack_linearity(stack_dir);
  const fs::path manifest = stack_dir / "manifest.json";
  StackResponse chosen;
  if (!response_file.empty()) {
    if (linearity.linearised_at_capture)
      fail(
          "{}: radiometry.response_applied: the capture already linearised the frames; solve without "
          "--response {}",
          manifest.string(), response_file.string());
    chosen.response = InverseResponse::load(response_file);
    logger("host")->debug("radiometry: frames linearised with {}", response_file.string());
    chosen.description = {
        {"applied", true}, {"source", "file"}, {"file", response_file.string()}, {"linear", true}};
    return chosen;
  }
  if (linearity.linearised_at_capture) {
    logger("host")->debug("radiometry: frames were linearised at capture");
    chosen.description = {{"applied", false}, {"source", "capture"}, {"linear", true}};
    return chosen;
  }
  if (linearity.response) {
    chosen.response = linearity.response;
    logger("host")->debug("radiometry: frames linearised with the response recorded in {}",
                          manifest.string());
    chosen.description = {{"applied", true}, {"source", "manifest"}, {"linear", true}};
    return chosen;
  }
  if (!linearity.linear) {
    logger("host")->warn(
        "{}: the frames are not linear ({}) and no camera response is known: normals will be biased; "
        "calibrate one with `lightstage camera response` and solve with --response FILE",
        manifest.string(),
        linearity.sensor_response.empty() ? "radiometry.linear is false"
                                          : "sensor response " + linearity.sensor_response);
    chosen.description = {{"applied", false}, {"source", "none"}, {"linear", false}};
    return chosen;
  }
  chosen.description = {{"applied", false}, {"source", "none"}, {"linear", true}};
  return chosen;
}

nlohmann::json linearise_stack(const fs::path& stack_dir, ImageStack& stack, const fs::path& response_file) {
  const StackResponse chosen = choose_stack_response(stack_dir, response_file);
  if (chosen.response) apply_response(*chosen.response, stack, stack_dir.string());
  return chosen.description;
}

}  // namespace lightstage
