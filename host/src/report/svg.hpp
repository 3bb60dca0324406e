#pragma once
// The report's plots, written as inline SVG by our own code: the lights on
// the hemisphere, histograms, bar charts and colour bars.

#include "lightstage/common/geometry.hpp"

#include <numbers>
#include <string>
#include <vector>

namespace lightstage::report {

// Degrees per radian.
inline constexpr double kDeg = 180.0 / std::numbers::pi;

struct PlotLight {
  Vec3 direction = Vec3::UnitZ();  // object -> light, camera frame (x right, y up, z to the camera)
  std::string label;               // shown on hover, e.g. "001.png · LED 17"
};

struct LightSeries {
  std::string name;    // legend text
  std::string colour;  // CSS colour
  bool cross = false;  // marker: false = filled dot, true = cross
  std::vector<PlotLight> lights;
};

// A polar plot of the hemisphere seen from the camera: azimuth around (0° =
// +x, to the right; 90° = +y, up), elevation from 0° at the rim to 90° at the
// centre. When `link_first_two`, light i of series 0 and 1 are joined by a line
// (nominal -> calibrated).
std::string hemisphere_svg(const std::vector<LightSeries>& series, bool link_first_two, int size = 440);

// Counts of values over [0, high] in counts.size() - 1 bins, the values at or
// above `high` in a last, marked bin: filled a band of values at a time.
class HistogramCounts {
 public:
  HistogramCounts(double high, int bins);
  void add(float value);  // not finite: not counted
  double high() const { return high_; }
  const std::vector<std::size_t>& counts() const { return counts_; }

 private:
  double high_;
  std::vector<std::size_t> counts_;
};

std::string histogram_svg(const HistogramCounts& histogram, const std::string& x_label);

// Bars, one per entry, against their index (1-based labels); `high` is the
// top of the y axis (≤ 0: the largest value).
std::string bar_chart_svg(const std::vector<double>& values, double high, const std::string& y_label,
                          const std::string& x_label, const std::string& colour);

// A horizontal colour bar of an OpenCV colour map from `low` to `high`; `id`
// names its gradient and must be unique in the page.
std::string colour_bar_svg(int colormap, double low, double high, const std::string& label,
                           const std::string& id);

}  // namespace lightstage::report
