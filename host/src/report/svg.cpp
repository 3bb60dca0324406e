#include "report/svg.hpp"

#include "report/html.hpp"
#include "report/maps.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace lightstage::report {

namespace {

std::string css_colour(const cv::Vec3b& bgr) {
  return fmt::format("#{:02x}{:02x}{:02x}", bgr[2], bgr[1], bgr[0]);
}

// Ticks 0, step, 2·step, ... ≤ high, about `count` of them.
std::vector<double> ticks(double high, int count) {
  const double step = nice_ceiling(high / std::max(count, 1));
  std::vector<double> out;
  for (int i = 0; i * step <= high * (1 + 1e-9); ++i) out.push_back(i * step);
  return out;
}

// The x axis, both axis labels and the end of a chart's SVG.
struct ChartFrame {
  int width, height, left, right, top;
  double plot_w, plot_h;
};
std::string close_chart(const ChartFrame& f, const std::string& x_label, const std::string& y_label) {
  std::string svg = fmt::format("<line x1=\"{0}\" y1=\"{1}\" x2=\"{2}\" y2=\"{1}\" stroke=\"#1d232b\"/>",
                                f.left, f.top + f.plot_h, f.width - f.right);
  svg += fmt::format(
      "<text x=\"{}\" y=\"{}\" font-size=\"12\" fill=\"#1d232b\" text-anchor=\"middle\">{}</text>",
      f.left + f.plot_w / 2, f.height - 6, escape_html(x_label));
  svg += fmt::format(
      "<text transform=\"translate(14 {}) rotate(-90)\" font-size=\"12\" fill=\"#1d232b\" "
      "text-anchor=\"middle\">{}</text>\n</svg>\n",
      f.top + f.plot_h / 2, escape_html(y_label));
  return svg;
}

}  // namespace

std::string hemisphere_svg(const std::vector<LightSeries>& series, bool link_first_two, int size) {
  const double c = size / 2.0, r = size / 2.0 - 34;
  const auto position = [&](const Vec3& d) {
    const Vec3 n = d.normalized();
    const double elevation = std::asin(std::clamp(n.z(), -1.0, 1.0)) * kDeg;
    const double azimuth = std::atan2(n.y(), n.x());
    const double radius = std::min(1.15, (90.0 - elevation) / 90.0) * r;
    return std::pair{c + radius * std::cos(azimuth), c - radius * std::sin(azimuth)};
  };
  std::string svg = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"plot\" width=\"{0}\" height=\"{1}\" viewBox=\"0 0 "
      "{0} {1}\" "
      "role=\"img\" aria-label=\"light directions on the hemisphere\">\n",
      size, size + 22 * static_cast<int>(series.size()));
  svg += fmt::format("<circle cx=\"{0}\" cy=\"{0}\" r=\"{1}\" fill=\"#f5f6f8\" stroke=\"#59606b\"/>\n", c, r);
  for (const int elevation : {30, 60}) {
    svg += fmt::format(
        "<circle cx=\"{0}\" cy=\"{0}\" r=\"{1:.2f}\" fill=\"none\" stroke=\"#c4c9d1\" stroke-dasharray=\"3 "
        "3\"/>"
        "<text x=\"{2:.1f}\" y=\"{3:.1f}\" font-size=\"11\" fill=\"#5d6673\">{4}°</text>\n",
        c, r * (90 - elevation) / 90.0, c + 3, c - r * (90 - elevation) / 90.0 - 3, elevation);
  }
  for (int azimuth = 0; azimuth < 360; azimuth += 45) {
    const double a = azimuth / kDeg;
    svg += fmt::format("<line x1=\"{0}\" y1=\"{0}\" x2=\"{1:.2f}\" y2=\"{2:.2f}\" stroke=\"#d9dde3\"/>", c,
                       c + r * std::cos(a), c - r * std::sin(a));
    svg += fmt::format(
        "<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"11\" fill=\"#5d6673\" text-anchor=\"middle\" "
        "dominant-baseline=\"middle\">{}°</text>\n",
        c + (r + 17) * std::cos(a), c - (r + 17) * std::sin(a), azimuth);
  }
  svg += fmt::format(
      "<text x=\"{0}\" y=\"{0}\" font-size=\"10\" fill=\"#5d6673\" text-anchor=\"middle\" "
      "dy=\"14\">90°</text>\n",
      c);
  if (link_first_two && series.size() >= 2) {
    const auto count = std::min(series[0].lights.size(), series[1].lights.size());
    for (std::size_t i = 0; i < count; ++i) {
      const auto [x0, y0] = position(series[0].lights[i].direction);
      const auto [x1, y1] = position(series[1].lights[i].direction);
      svg += fmt::format("<line x1=\"{:.2f}\" y1=\"{:.2f}\" x2=\"{:.2f}\" y2=\"{:.2f}\" stroke=\"#9aa3af\"/>",
                         x0, y0, x1, y1);
    }
    svg += "\n";
  }
  for (const auto& s : series) {
    svg += fmt::format("<g class=\"series\" fill=\"{0}\" stroke=\"{0}\">", escape_html(s.colour));
    for (const auto& light : s.lights) {
      const auto [x, y] = position(light.direction);
      const Vec3 n = light.direction.normalized();
      const std::string title =
          fmt::format("{}: {} (azimuth {:.1f}°, elevation {:.1f}°)", s.name, light.label,
                      std::fmod(std::atan2(n.y(), n.x()) * kDeg + 360.0, 360.0),
                      std::asin(std::clamp(n.z(), -1.0, 1.0)) * kDeg);
      if (s.cross) {
        svg += fmt::format(
            "<path d=\"M{0:.2f} {1:.2f}l8 8m0 -8l-8 8\" transform=\"translate(-4 -4)\" stroke-width=\"2\" "
            "fill=\"none\"><title>{2}</title></path>",
            x, y, escape_html(title));
      } else {
        svg += fmt::format(
            "<circle cx=\"{:.2f}\" cy=\"{:.2f}\" r=\"4\" stroke=\"none\"><title>{}</title></circle>", x, y,
            escape_html(title));
      }
    }
    svg += "</g>\n";
  }
  for (std::size_t i = 0; i < series.size(); ++i) {
    const double y = size + 22.0 * static_cast<double>(i) + 6;
    const auto& s = series[i];
    if (s.cross) {
      svg += fmt::format("<path d=\"M12 {0:.1f}l8 8m0 -8l-8 8\" stroke=\"{1}\" stroke-width=\"2\"/>", y,
                         escape_html(s.colour));
    } else {
      svg +=
          fmt::format("<circle cx=\"16\" cy=\"{:.1f}\" r=\"4\" fill=\"{}\"/>", y + 4, escape_html(s.colour));
    }
    svg +=
        fmt::format("<text x=\"28\" y=\"{:.1f}\" font-size=\"13\" fill=\"#1d232b\">{} ({} lights)</text>\n",
                    y + 8, escape_html(s.name), s.lights.size());
  }
  svg += "</svg>\n";
  return svg;
}

HistogramCounts::HistogramCounts(double high, int bins)
    : high_(high > 0 ? high : 1.0), counts_(static_cast<std::size_t>(std::max(bins, 1)) + 1, 0) {}

void HistogramCounts::add(float value) {
  if (!std::isfinite(value)) return;
  const int n = static_cast<int>(counts_.size()) - 1;
  const auto bin = value >= high_ ? n : std::clamp(static_cast<int>(value / high_ * n), 0, n - 1);
  ++counts_[static_cast<std::size_t>(bin)];
}

std::string histogram_svg(const HistogramCounts& histogram, const std::string& x_label) {
  const int width = 460, height = 240, left = 56, right = 16, top = 12, bottom = 44;
  const double top_value = histogram.high();
  const auto& counts = histogram.counts();
  const int n = static_cast<int>(counts.size()) - 1;
  const double peak =
      static_cast<double>(std::max<std::size_t>(1, *std::max_element(counts.begin(), counts.end())));
  const double plot_w = width - left - right, plot_h = height - top - bottom;
  const double bar_w = plot_w / (n + 1);
  std::string svg = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"plot\" width=\"{0}\" height=\"{1}\" viewBox=\"0 0 "
      "{0} {1}\" "
      "role=\"img\" aria-label=\"histogram of {2}\">\n",
      width, height, escape_html(x_label));
  const double y_top = nice_ceiling(peak);
  for (const double t : ticks(y_top, 4)) {
    const double y = top + plot_h * (1 - t / y_top);
    svg += fmt::format(
        "<line x1=\"{0}\" y1=\"{1:.1f}\" x2=\"{2}\" y2=\"{1:.1f}\" stroke=\"#e3e6ea\"/><text x=\"{3}\" "
        "y=\"{1:.1f}\" "
        "font-size=\"11\" fill=\"#5d6673\" text-anchor=\"end\" dominant-baseline=\"middle\">{4}</text>\n",
        left, y, width - right, left - 6, format_number(t));
  }
  for (int i = 0; i <= n; ++i) {
    const double h = plot_h * static_cast<double>(counts[static_cast<std::size_t>(i)]) / y_top;
    const bool overflow = i == n;
    svg += fmt::format(
        "<rect x=\"{:.2f}\" y=\"{:.2f}\" width=\"{:.2f}\" height=\"{:.2f}\" fill=\"{}\"><title>{}: {} "
        "pixels</title></rect>",
        left + i * bar_w + 0.5, top + plot_h - h, std::max(bar_w - 1, 0.5), h,
        overflow ? "#c2410c" : "#3b6fb6",
        overflow ? fmt::format("≥ {}", format_number(top_value))
                 : fmt::format("{} – {}", format_number(top_value * i / n),
                               format_number(top_value * (i + 1) / n)),
        counts[static_cast<std::size_t>(i)]);
  }
  svg += "\n";
  for (const double t : ticks(top_value, 5)) {
    const double x = left + plot_w * (t / top_value) * n / (n + 1);
    svg += fmt::format(
        "<line x1=\"{0:.1f}\" y1=\"{1}\" x2=\"{0:.1f}\" y2=\"{2}\" stroke=\"#5d6673\"/><text x=\"{0:.1f}\" "
        "y=\"{3}\" "
        "font-size=\"11\" fill=\"#5d6673\" text-anchor=\"middle\">{4}</text>\n",
        x, top + plot_h, top + plot_h + 4, top + plot_h + 16, format_number(t));
  }
  svg += fmt::format(
      "<text x=\"{:.1f}\" y=\"{}\" font-size=\"11\" fill=\"#c2410c\" text-anchor=\"middle\">≥</text>\n",
      left + plot_w - bar_w / 2, top + plot_h + 16);
  svg += close_chart({width, height, left, right, top, plot_w, plot_h}, x_label, "pixels");
  return svg;
}

std::string bar_chart_svg(const std::vector<double>& values, double high, const std::string& y_label,
                          const std::string& x_label, const std::string& colour) {
  const int width = 640, height = 200, left = 56, right = 12, top = 10, bottom = 40;
  double top_value = high;
  if (!(top_value > 0)) {
    top_value = 0;
    for (const double v : values)
      if (std::isfinite(v)) top_value = std::max(top_value, v);
    top_value = nice_ceiling(top_value);
  }
  const double plot_w = width - left - right, plot_h = height - top - bottom;
  const double bar_w = plot_w / static_cast<double>(std::max<std::size_t>(values.size(), 1));
  std::string svg = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"plot\" width=\"{0}\" height=\"{1}\" viewBox=\"0 0 "
      "{0} {1}\" "
      "role=\"img\" aria-label=\"{2} per light\">\n",
      width, height, escape_html(y_label));
  for (const double t : ticks(top_value, 4)) {
    const double y = top + plot_h * (1 - t / top_value);
    svg += fmt::format(
        "<line x1=\"{0}\" y1=\"{1:.1f}\" x2=\"{2}\" y2=\"{1:.1f}\" stroke=\"#e3e6ea\"/><text x=\"{3}\" "
        "y=\"{1:.1f}\" "
        "font-size=\"11\" fill=\"#5d6673\" text-anchor=\"end\" dominant-baseline=\"middle\">{4}</text>\n",
        left, y, width - right, left - 6, format_number(t));
  }
  for (std::size_t i = 0; i < values.size(); ++i) {
    const double v = std::isfinite(values[i]) ? std::clamp(values[i], 0.0, top_value) : 0.0;
    const double h = plot_h * v / top_value;
    svg += fmt::format(
        "<rect x=\"{:.2f}\" y=\"{:.2f}\" width=\"{:.2f}\" height=\"{:.2f}\" fill=\"{}\"><title>light {}: "
        "{}</title></rect>",
        left + static_cast<double>(i) * bar_w + 0.25, top + plot_h - h, std::max(bar_w - 0.5, 0.5), h,
        escape_html(colour), i + 1, format_number(values[i]));
  }
  svg += "\n";
  const std::size_t step = std::max<std::size_t>(
      1, static_cast<std::size_t>(nice_ceiling(static_cast<double>(values.size()) / 12.0)));
  for (std::size_t i = 0; i < values.size(); i += step) {
    svg += fmt::format(
        "<text x=\"{:.1f}\" y=\"{}\" font-size=\"11\" fill=\"#5d6673\" text-anchor=\"middle\">{}</text>",
        left + (static_cast<double>(i) + 0.5) * bar_w, top + plot_h + 14, i + 1);
  }
  svg += close_chart({width, height, left, right, top, plot_w, plot_h}, x_label, y_label);
  return svg;
}

std::string colour_bar_svg(int colormap, double low, double high, const std::string& label,
                           const std::string& id) {
  const int width = 360, height = 56, left = 10, right = 10, bar_h = 14;
  const auto samples = colormap_samples(colormap, 17);
  std::string svg = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"plot colour-bar\" width=\"{0}\" height=\"{1}\" "
      "viewBox=\"0 0 {0} {1}\" role=\"img\" aria-label=\"colour bar: {2}\">\n<defs><linearGradient "
      "id=\"{3}\">",
      width, height, escape_html(label), escape_html(id));
  for (std::size_t i = 0; i < samples.size(); ++i) {
    svg += fmt::format("<stop offset=\"{:.4f}\" stop-color=\"{}\"/>",
                       static_cast<double>(i) / (samples.size() - 1), css_colour(samples[i]));
  }
  const double plot_w = width - left - right;
  svg += fmt::format(
      "</linearGradient></defs>\n<rect x=\"{}\" y=\"4\" width=\"{}\" height=\"{}\" fill=\"url(#{})\" "
      "stroke=\"#59606b\"/>\n",
      left, plot_w, bar_h, escape_html(id));
  const double span = high > low ? high - low : 1.0;
  for (const double t : ticks(span, 5)) {
    const double x = left + plot_w * t / span;
    svg += fmt::format(
        "<line x1=\"{0:.1f}\" y1=\"{1}\" x2=\"{0:.1f}\" y2=\"{2}\" stroke=\"#1d232b\"/><text x=\"{0:.1f}\" "
        "y=\"{3}\" "
        "font-size=\"11\" fill=\"#1d232b\" text-anchor=\"middle\">{4}</text>",
        x, 4 + bar_h, 8 + bar_h, 20 + bar_h, format_number(low + t));
  }
  svg += fmt::format(
      "\n<text x=\"{}\" y=\"{}\" font-size=\"12\" fill=\"#5d6673\" "
      "text-anchor=\"middle\">{}</text>\n</svg>\n",
      left + plot_w / 2, height - 4, escape_html(label));
  return svg;
}

}  // namespace lightstage::report
