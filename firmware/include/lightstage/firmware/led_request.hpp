#pragma once
// The checks an LED list from the host passes before anything is lit, shared
// by SetLeds and by each step of an uploaded sequence.

#include "lightstage/common/rig.hpp"
#include "lightstage/proto/controller.pb.h"

#include <optional>
#include <string>

namespace lightstage::firmware {

// Why `leds` cannot be lit on `rig` (an LED the rig does not have, one listed
// twice, a level outside 0..1, or one between 0 and 1, which these drivers
// cannot dim), or nullopt when every entry is fine. The first problem found
// wins. `step`: the sequence step the list belongs to, named at the start of
// the message ("step 2: ..."); nullopt for a SetLeds request.
std::optional<std::string> led_levels_problem(const Rig& rig,
                                              const google::protobuf::RepeatedPtrField<proto::LedLevel>& leds,
                                              std::optional<int> step = std::nullopt);

}  // namespace lightstage::firmware
