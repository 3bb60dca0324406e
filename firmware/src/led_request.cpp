#include "lightstage/firmware/led_request.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <set>

namespace lightstage::firmware {

std::optional<std::string> led_levels_problem(const Rig& rig,
                                              const google::protobuf::RepeatedPtrField<proto::LedLevel>& leds,
                                              std::optional<int> step) {
  const std::string where = step ? fmt::format("step {}: ", *step) : std::string();
  std::set<std::uint32_t> seen;
  for (const auto& led : leds) {
    // The level messages differ by one colon between the two requests ("LED 3: level" for
    // SetLeds, "step 2: LED 3 level" in a sequence); both are kept as the host has seen them.
    const std::string who =
        step ? fmt::format("{}LED {}", where, led.led_id()) : fmt::format("LED {}:", led.led_id());
    const bool known = std::any_of(rig.leds.begin(), rig.leds.end(),
                                   [&](const Led& l) { return l.id == static_cast<int>(led.led_id()); });
    if (!known) return fmt::format("{}rig '{}' has no LED {}", where, rig.name, led.led_id());
    if (!seen.insert(led.led_id()).second) return fmt::format("{}LED {} listed twice", where, led.led_id());
    if (!(led.level() >= 0 && led.level() <= 1))
      return fmt::format("{} level {} outside 0..1", who, led.level());
    if (led.level() > 0 && led.level() < 1) {
      return fmt::format("{} level {}: these LED drivers cannot dim (levels are 0 or 1)", who, led.level());
    }
  }
  return std::nullopt;
}

}  // namespace lightstage::firmware
