#include "lightstage/host/calibration/calibration_output.hpp"

#include "io/text_table.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/host/calibration/calibration_plot.hpp"
#include "lightstage/host/calibration/lp_file.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "util/atomic_file.hpp"

#include <algorithm>

namespace lightstage::calibration {

nlohmann::json DirectionComparison::to_json() const {
  return {{"mean_deg", mean_deg}, {"median_deg", median_deg}, {"max_deg", max_deg}, {"count", count}};
}

DirectionComparison compare_directions(const LightCalibration& calibration,
                                       const std::filesystem::path& reference) {
  const auto rows = io::read_vec3_rows(reference);
  if (rows.size() != calibration.lights.size())
    fail("{}: {} direction line(s), but the calibration has {} lights", reference.string(), rows.size(),
         calibration.lights.size());
  DirectionComparison result;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (!calibration.lights[i].measured) continue;
    if (!(rows[i].value.norm() > 0)) fail("{}:{}: zero-length direction", reference.string(), rows[i].number);
    result.per_light_deg.push_back(angle_between_deg(rows[i].value, calibration.lights[i].direction));
  }
  result.count = result.per_light_deg.size();
  if (result.count == 0) return result;
  std::vector<double> sorted = result.per_light_deg;
  std::sort(sorted.begin(), sorted.end());
  for (const double a : sorted) result.mean_deg += a / static_cast<double>(sorted.size());
  result.median_deg = sorted[sorted.size() / 2];
  result.max_deg = sorted.back();
  return result;
}

nlohmann::json write_calibration_outputs(const std::filesystem::path& out, const LightCalibrationRun& run,
                                         const std::vector<std::filesystem::path>& inputs) {
  const LightCalibration& cal = run.calibration;
  std::error_code error;
  std::filesystem::create_directories(out, error);
  if (error) fail("{}: cannot create folder: {}", out.string(), error.message());
  write_calibration(out / "calibration.json", cal);
  util::write_text_atomic(out / "light_directions.txt", directions_text(cal));
  util::write_text_atomic(out / "light_intensities.txt", intensities_text(cal));
  std::vector<LpEntry> lp;
  for (const auto& light : cal.lights) {
    if (light.measured) lp.push_back({light.image, light.direction});
  }
  util::write_text_atomic(out / "lights.lp", format_lp(lp));
  io::write_png(out / "lights_hemisphere.png", hemisphere_plot(cal));
  for (std::size_t k = 0; k < run.sphere_views.size() && k < inputs.size(); ++k) {
    const std::string name =
        run.sphere_views.size() == 1 ? "highlights.png" : fmt::format("highlights_{}.png", k + 1);
    io::write_png(out / name, highlight_overlay(run.sphere_views[k], cal, inputs[k]));
  }
  if (!run.flat_field.empty()) io::write_pfm(out / "flat_field.pfm", run.flat_field);

  std::size_t measured = 0;
  double worst_residual = 0;
  for (const auto& light : cal.lights) {
    if (!light.measured) continue;
    ++measured;
    if (light.position_mm) worst_residual = std::max(worst_residual, light.position_residual_mm);
  }
  nlohmann::json summary{{"out", out.string()},           {"lights", cal.lights.size()},
                         {"measured", measured},          {"direction_method", cal.direction_method},
                         {"spheres", cal.spheres.size()}, {"problems", cal.problems.size()},
                         {"seconds", run.seconds}};
  if (cal.has_positions()) summary["max_position_residual_mm"] = worst_residual;
  if (cal.nominal_fit) summary["nominal_fit"] = cal.nominal_fit->to_json();
  return summary;
}

}  // namespace lightstage::calibration
