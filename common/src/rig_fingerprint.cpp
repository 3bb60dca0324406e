#include "lightstage/common/rig_fingerprint.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdint>
#include <vector>

namespace lightstage {
namespace {

std::string number(double value) { return fmt::format("{:.17g}", value); }

std::string vec3(const Vec3& v) { return number(v.x()) + " " + number(v.y()) + " " + number(v.z()); }

// Names are written with their length first, so no name can imitate a field boundary.
std::string text(const std::string& value) { return fmt::format("{}:{}", value.size(), value); }

std::string line_ref(const LineRef& line) {
  return (line.by_name() ? "name " + text(line.name) : "offset " + std::to_string(line.offset)) +
         (line.active_low ? " active_low" : " active_high");
}

std::string limits(const LedLimits& l) {
  return number(l.max_on_us) + " " + number(l.max_duty) + " " + number(l.duty_window_us);
}

}  // namespace

std::string canonical_rig_text(const Rig& rig) {
  std::string out = "lightstage-rig 1\n";
  auto add = [&out](const std::string& key, const std::string& value) { out += key + " " + value + "\n"; };
  add("name", text(rig.name));
  add("dome_radius_mm", number(rig.dome_radius_mm));
  add("object_position_mm", vec3(rig.object_position_mm));
  const CameraDefaults& cam = rig.camera;
  add("camera",
      fmt::format("{} {}x{} pitch {} focal {} at {} exposure {} gain {} bits {} uri {}",
                  cam.model == CameraModel::kPinhole ? "pinhole" : "orthographic", cam.width, cam.height,
                  number(cam.pixel_pitch_mm), number(cam.focal_px), vec3(cam.position_mm),
                  number(cam.exposure_us), number(cam.gain), cam.bit_depth, text(cam.uri)));
  add("trigger", line_ref(rig.trigger.line) + " pulse " + number(rig.trigger.pulse_us));
  add("strobe",
      rig.strobe ? line_ref(rig.strobe->line) + " timeout " + number(rig.strobe->timeout_us) : "none");

  std::vector<const ShiftRegisterChain*> chains;
  for (const auto& c : rig.chains) chains.push_back(&c);
  std::sort(chains.begin(), chains.end(), [](auto* a, auto* b) { return a->name < b->name; });
  for (const auto* c : chains) {
    add("chain", fmt::format("{} data {} clock {} latch {} oe {} length {} period {}", text(c->name),
                             line_ref(c->data), line_ref(c->clock), line_ref(c->latch),
                             c->output_enable ? line_ref(*c->output_enable) : "none", c->length,
                             number(c->clock_period_us)));
  }

  std::vector<const Led*> leds;
  for (const auto& led : rig.leds) leds.push_back(&led);
  std::sort(leds.begin(), leds.end(), [](auto* a, auto* b) { return a->id < b->id; });
  for (const auto* led : leds) {
    const std::string wiring =
        std::holds_alternative<DirectWiring>(led->wiring)
            ? "line " + line_ref(std::get<DirectWiring>(led->wiring).line)
            : fmt::format("chain {} bit {}", text(std::get<ChainWiring>(led->wiring).chain),
                          std::get<ChainWiring>(led->wiring).bit);
    add("led", fmt::format("{} at {} {} colour {} wavelength {} intensity {} limits {}", led->id,
                           vec3(led->position_mm), wiring, text(led->colour),
                           led->wavelength_nm ? number(*led->wavelength_nm) : "none",
                           number(led->relative_intensity), limits(led->limits)));
  }
  return out;
}

std::string content_hash(std::string_view bytes) {
  std::uint64_t hash = 14695981039346656037ull;  // FNV-1a 64-bit offset basis
  for (const unsigned char c : bytes) {
    hash ^= c;
    hash *= 1099511628211ull;  // FNV prime
  }
  return fmt::format("{:016x}", hash);
}

std::string rig_fingerprint(const Rig& rig) { return content_hash(canonical_rig_text(rig)); }

}  // namespace lightstage
