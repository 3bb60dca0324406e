#pragma once
// Which camera response a stack's frames need before radiometry, from its
// manifest (docs/stack-format.md, "radiometry") or a response file the user
// gives (`lightstage camera response`), and applying it: frames, darks,
// black and saturation levels become relative linear radiance (float, full
// scale 1), so make_observations treats them like any linear float stack.

#include "lightstage/common/image_stack.hpp"
#include "lightstage/host/capture/response_curve.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <optional>
#include <string>

namespace lightstage {

// What the manifest says about its frames' linearity.
struct StackLinearity {
  bool linear = true;  // frames are linear as stored (raw sensor or linearised at capture)
  bool linearised_at_capture = false;
  std::optional<InverseResponse> response;  // recorded but not applied to the frames
  std::string sensor_response;              // the simulator's sensor curve, when recorded
};

// Reads `radiometry` (and the simulator's `sensor.response`) from
// STACK_DIR/manifest.json; absent keys = linear. Throws InputError naming the
// file and field when a key has the wrong type.
StackLinearity read_stack_linearity(const std::filesystem::path& stack_dir);

// Linearises every frame (and its dark, black and saturation levels) with
// `response`. Throws InputError naming the frame when it is not 8- or 16-bit.
void apply_response(const InverseResponse& response, ImageStack& stack, const std::string& where);

// The response solve applies to the stack in `stack_dir` (nothing when the
// frames are linear or were linearised at capture) and what linearise_stack
// returns for it, without touching any frame: a stack read in bands applies
// it to each band (apply_response).
struct StackResponse {
  std::optional<InverseResponse> response;
  nlohmann::json description;
};
StackResponse choose_stack_response(const std::filesystem::path& stack_dir,
                                    const std::filesystem::path& response_file);

// The response solve uses for the stack in `stack_dir`: `response_file` when
// given (an error when the capture already linearised the frames), otherwise
// the one the manifest recorded and did not apply. Applies it and returns what
// was done, for summary.json: {"applied": bool, "source": "file"|"manifest"|
// "capture"|"none", "linear": bool, "file": ...}. Warns, naming the fix, when
// the manifest says the frames are non-linear and no response is known.
nlohmann::json linearise_stack(const std::filesystem::path& stack_dir, ImageStack& stack,
                               const std::filesystem::path& response_file);

}  // namespace lightstage
