#pragma once
// One calibration, many captures: `lightstage solve --calibration FILE`
// replaces a stack's light directions with calibrated ones and, when the
// calibration measured them, its relative light intensities (the stack's
// overall scale and each frame's exposure × gain are kept), and — when the
// calibration holds LED positions — gives the solver near lights: per pixel,
// the direction to each LED and its 1/d² falloff, with the surface first
// taken as the plane through the object position.
//
// FILE is a calibration.json or an RTI .lp file (directions only). Lights are
// matched to frames by LED id when both know them, by file name (.lp), else
// by order (the counts must agree).

#include "lightstage/common/image_stack.hpp"
#include "lightstage/host/calibration/light_calibration.hpp"
#include "lightstage/host/radiometry.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <optional>

namespace lightstage::calibration {

struct StackCalibration {
  std::filesystem::path file;
  LightCalibration calibration;                // from an .lp file: directions only
  std::vector<std::size_t> light_of_frame;     // per frame, its light in calibration.lights
  std::string matched_by;                      // "led_id", "filename" or "order"
  std::optional<CameraGeometry> stack_camera;  // the stack's own (manifest), when it records one
  bool intensities_replaced = false;           // the calibration measured intensities

  nlohmann::json describe() const;
};

// Reads `file`, matches its lights to the frames of `stack` (loaded from
// `stack_dir`) and rewrites their light directions and intensities. Throws
// InputError naming the file and the frame when they cannot be matched or a
// matched light was not measured.
StackCalibration apply_calibration_file(const std::filesystem::path& file,
                                        const std::filesystem::path& stack_dir, ImageStack& stack);

// Sets observations.near from the calibration's LED positions (surface points
// on the plane z = plane_z_mm, default the calibration's object position).
// Returns false (and leaves `observations` alone) when it holds no positions.
// Throws InputError when the stack's camera is unknown and differs in size
// from the calibration's.
bool set_near_lights(const StackCalibration& calibration, Observations& observations,
                     std::optional<double> plane_z_mm = std::nullopt);

// Sets observations.near from the stack's own LED positions (manifest
// frames[i].led_position_mm, every frame) and the camera its manifest records;
// the object centre, where the stack's intensities hold, is where the frames'
// light directions from their LEDs meet (least squares), surface points on
// the plane through it. Returns false, with the reason in *why_not, when a
// frame has no position, the manifest records no metric camera or the
// directions do not meet.
bool set_stack_near_lights(const std::filesystem::path& stack_dir, const ImageStack& stack,
                           Observations& observations, std::string* why_not);

}  // namespace lightstage::calibration
