#include "lightstage/host/report/light_statistics.hpp"

#include "lightstage/common/error.hpp"

#include <cmath>

namespace lightstage::report {

nlohmann::json LightStatistics::to_json() const {
  return {{"file", file},
          {"led_id", led_id},
          {"direction", {direction.x(), direction.y(), direction.z()}},
          {"exposure_us", exposure_us},
          {"gain", gain},
          {"mean_value", mean_value},
          {"saturated_share", saturated_share},
          {"shadow_share", shadow_share}};
}

std::vector<LightStatistics> light_statistics(const ImageStack& stack, double shadow_threshold,
                                              const RadiometryOptions& radiometry) {
  return light_statistics(stack, make_observations(stack, radiometry), shadow_threshold);
}

std::vector<LightStatistics> light_statistics(const ImageStack& stack, const Observations& observations,
                                              double shadow_threshold) {
  if (!(shadow_threshold >= 0) || !std::isfinite(shadow_threshold))
    fail("light statistics: shadow_threshold must be a number ≥ 0, got {}", shadow_threshold);
  if (observations.image_count() != stack.frames.size())
    fail("light statistics: {} observation columns for {} frames", observations.image_count(),
         stack.frames.size());
  const auto pixels = static_cast<Eigen::Index>(observations.pixel_count());
  std::vector<LightStatistics> out;
  for (std::size_t i = 0; i < stack.frames.size(); ++i) {
    const Frame& frame = stack.frames[i];
    const auto column = static_cast<Eigen::Index>(i);
    LightStatistics s;
    s.file = frame.filename;
    s.led_id = frame.led_id;
    s.direction = frame.light_direction;
    s.exposure_us = frame.exposure_us;
    s.gain = frame.gain;
    if (pixels > 0) {
      double sum = 0;
      Eigen::Index saturated = 0, shadow = 0;
      for (Eigen::Index p = 0; p < pixels; ++p) {
        const float v = observations.intensities(p, column);
        sum += v;
        if (observations.saturated(p, column)) ++saturated;
        if (v <= shadow_threshold) ++shadow;
      }
      const auto n = static_cast<double>(pixels);
      s.mean_value = sum / n;
      s.saturated_share = static_cast<double>(saturated) / n;
      s.shadow_share = static_cast<double>(shadow) / n;
    }
    out.push_back(s);
  }
  return out;
}

}  // namespace lightstage::report
