#pragma once
// Per-light statistics of a stack, for the report: did every LED fire, how
// much of the object each light clips or leaves in shadow. Computed from the
// radiometry's values (host/radiometry.hpp) over the pixels inside the mask.

#include "lightstage/common/image_stack.hpp"
#include "lightstage/host/radiometry.hpp"

#include <nlohmann/json.hpp>

#include <optional>
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

// The frames' image names, in order (what a tally counts).
std::vector<std::string> frame_files(const ImageStack& stack);

// The shadow threshold the statistics use: `flag` when given, else the
// solver's (a solve's parameters.shadow_threshold when > 0), else 0.02.
struct StatisticsThreshold {
  double value = 0;
  std::string source;  // "--shadow-threshold", "the solver's" or "the default"
};
StatisticsThreshold statistics_threshold(const nlohmann::json& solve_parameters,
                                         std::optional<double> flag = std::nullopt);

// The statistics gathered where the observations are made: by the solve, a
// band (or a tile) at a time, so that the report never decodes the stack
// again. Sums and counts add exactly; `summary_json` is what summary.json
// records under "light_statistics" and the report reads back.
class LightStatisticsTally {
 public:
  LightStatisticsTally(std::vector<std::string> files, StatisticsThreshold threshold);

  // Observations of some of the mask's pixels, one column per file.
  void add(const Observations& observations);
  // Another part of the same stack's pixels (a tile job's, counted with the same threshold).
  void add(const LightStatisticsTally& other);
  // One entry per frame of `stack` (the frames counted, in order).
  std::vector<LightStatistics> statistics(const ImageStack& stack) const;

  // {"shadow_threshold", "threshold_source", "pixels", "frames": [{"file", "mean_value",
  // "saturated_share", "shadow_share"}]}
  nlohmann::json summary_json() const;
  // Sums and counts, exactly; `from_json` reads them back (InputError naming `what`).
  nlohmann::json to_json() const;
  static LightStatisticsTally from_json(const nlohmann::json& j, const std::string& what);

 private:
  std::vector<std::string> files_;
  StatisticsThreshold threshold_;
  std::size_t pixels_ = 0;
  std::vector<double> sums_;
  std::vector<std::size_t> saturated_, shadow_;
};

// The threshold statistics a solve recorded were made with; nullopt when
// absent or malformed.
std::optional<StatisticsThreshold> recorded_threshold(const nlohmann::json& recorded);

// Statistics a solve recorded (LightStatisticsTally::summary_json) for the
// frames of `stack`, its metadata (LED, direction, exposure) from `stack`.
// nullopt when they are absent, malformed or were made of other frames.
std::optional<std::vector<LightStatistics>> recorded_light_statistics(const nlohmann::json& recorded,
                                                                      const ImageStack& stack);

}  // namespace lightstage::report
