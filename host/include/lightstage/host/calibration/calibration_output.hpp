#pragma once
// The files of `lightstage calibrate lights --out DIR`:
//   calibration.json        everything (light_calibration.hpp, docs/calibration.md)
//   light_directions.txt    "x y z" per measured light (DiLiGenT layout)
//   light_intensities.txt   "r g b" per measured light
//   lights.lp               RTI light positions: the count, then "filename x y z"
//   lights_hemisphere.png   calibrated (and nominal) lights on the hemisphere
//   highlights.png          the sphere view with outlines and highlights (highlights_<k>.png per stack)
//   flat_field.pfm          the flat field, when intensities came from a flat target
// and the comparison with reference directions when asked for.

#include "lightstage/host/calibration/calibrate_lights.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <vector>

namespace lightstage::calibration {

struct DirectionComparison {
  double mean_deg = 0, median_deg = 0, max_deg = 0;
  std::size_t count = 0;
  std::vector<double> per_light_deg;  // per measured light, in order

  nlohmann::json to_json() const;
};

// Angles between the calibration's measured directions and the rows of a
// reference light_directions.txt (one per light of the calibration).
DirectionComparison compare_directions(const LightCalibration& calibration,
                                       const std::filesystem::path& reference);

// Writes the files above into `out` (created if needed); returns a summary.
nlohmann::json write_calibration_outputs(const std::filesystem::path& out, const LightCalibrationRun& run,
                                         const std::vector<std::filesystem::path>& inputs);

}  // namespace lightstage::calibration
