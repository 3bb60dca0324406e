#pragma once
// Per-light statistics of a stack, for the report: did every LED fire, how
// much of the object each light clips or leaves in shadow. Computed from the
// radiometry's values (host/radiometry.hpp) over the pixels inside the mask.

#include "lightstage/common/image_stack.hpp"
#include "lightstage/host/radiometry.hpp"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace lightstage::report {

struct LightStatistics {
  std::string file;                // the frame's image, e.g. "001.png"
  int led_id = -1;                 // -1 when not from a rig
  Vec3 direction = Vec3::UnitZ();  // object -> light
  double exposure_us = 0;          // 0 when unknown
  double gain = 1;
  double mean_value = 0;       // mean radiometric value over the mask
  double saturated_share = 0;  // share of mask pixels with a raw channel at or above saturation
  double shadow_share = 0;     // share of mask pixels with value ≤ the shadow threshold

  nlohmann::json to_json() const;
};

// One entry per frame of `stack`, in order. `shadow_threshold` ≥ 0 (values are
// in the radiometry's units: linear, divided by the light's intensity).
std::vector<LightStatistics> light_statistics(const ImageStack& stack, double shadow_threshold,
                                              const RadiometryOptions& radiometry = {});

// The same from observations already made (their frames' metadata from `stack`).
std::vector<LightStatistics> light_statistics(const ImageStack& stack, const Observations& observations,
                                              double shadow_threshold);

}  // namespace lightstage::report
