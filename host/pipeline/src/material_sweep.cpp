#include "lightstage/pipeline/material_sweep.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/geometry.hpp"
#include "lightstage/host/eval/angular_error.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/shadow_threshold.hpp"
#include "lightstage/pipeline/solve_methods.hpp"
#include "lightstage/pipeline/synthetic_observations.hpp"
#include "lightstage/sim/material.hpp"

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>

namespace lightstage::pipeline {
namespace {

std::string noise_label(double lambda) {
  return lambda < 0 ? std::string("no noise") : fmt::format("lambda={:g}", lambda);
}

SolveResult run_method(const std::string& name, const Observations& obs,
                       const MaterialSweepOptions& options) {
  SolveSettings args;
  args.t_low = options.t_low;
  args.azimuth_from = options.azimuth_from;
  args.automatic.agreement_deg = options.auto_agreement_deg;
  args.automatic.monotonic_margin = options.auto_margin;
  args.monotonic.refine_step_deg = args.automatic.monotonic.refine_step_deg = options.refine_step_deg;
  args.monotonic.plateau_tolerance = options.plateau_tolerance;
  args.falloff = options.falloff;
  args.threads = options.threads;
  args.resolve();
  // The shadow threshold `solve` would estimate from these observations (shadow_threshold.hpp).
  args.use_data_shadow_threshold(estimate_shadow_threshold(obs).value);
  args.robust.t_low = RobustOptions{}.t_low;  // the robust method keeps its own selection
  if (name == "lambert-low") {
    args.l2.shadow_threshold = 1e-6;
    return solve_lambertian(obs, args.l2);
  }
  args.l2.t_low = 1.0;
  return find_solve_method(name).solve(obs, args);
}

}  // namespace

std::vector<std::string> default_sweep_materials() {
  return {"lambert",
          "oren-nayar:sigma=0.3",
          "oren-nayar:sigma=0.6",
          "blinn-phong:shininess=10,ks=0.3",
          "blinn-phong:shininess=50,ks=0.5",
          "blinn-phong:shininess=200,ks=0.7",
          "cook-torrance:roughness=0.1,ks=0.5",
          "cook-torrance:roughness=0.2,ks=0.5",
          "cook-torrance:roughness=0.3,ks=0.5",
          "cook-torrance:roughness=0.5,ks=0.5",
          "cook-torrance:roughness=0.8,ks=0.5",
          "ward:alpha=0.1,ks=0.5",
          "ward:alpha=0.2,ks=0.5",
          "ward:alpha=0.4,ks=0.5",
          "two-lobe-ct:k1=0.2,k2=0.8",
          "two-lobe-ct:k1=0.5,k2=0.5",
          "two-lobe-ct:k1=0.8,k2=0.2",
          "two-lobe-fabric:k1=0.5,k2=0.5",
          "two-lobe-fabric:k1=0.8,k2=0.2",
          "two-lobe-random:k1=0.8,k2=0.2",
          "two-lobe-random:k1=0.5,k2=0.5"};
}

std::vector<std::string> default_sweep_methods() {
  return {"l2", "lambert-low", "robust", "monotonic", "bilinear", "biquadratic", "bicubic", "auto"};
}

void MaterialSweepOptions::check() const {
  for (const auto& m : methods) {
    if (m != "lambert-low") find_solve_method(m);
  }
  for (const int n : light_counts) {
    if (n < 20 || n > 2000) fail("--lights: each count must be in [20, 2000], got {}", n);
  }
  for (const double l : noise) {
    if (!(l == -1 || (l >= 0 && l <= 1)))
      fail("--noise: each lambda must be in [0, 1] (or 'none'), got {}", l);
  }
  if (!(t_low > 0 && t_low <= 1)) fail("--t-low: must be in (0, 1], got {}", t_low);
  if (!(light_cone_deg >= 20 && light_cone_deg <= 90))
    fail("--light-cone: must be in [20, 90] degrees, got {}", light_cone_deg);
  if (threads < 0) fail("--threads: must be 0 (automatic) or positive, got {}", threads);
  parse_falloff(falloff);
}

std::size_t MaterialSweepOptions::cells() const {
  const std::size_t m = materials.empty() ? default_sweep_materials().size() : materials.size();
  const std::size_t k = methods.empty() ? default_sweep_methods().size() : methods.size();
  return light_counts.size() * noise.size() * m * k;
}

MaterialSweepResult run_material_sweep(const MaterialSweepOptions& given,
                                       const std::function<void(std::size_t)>& on_cells) {
  MaterialSweepResult result;
  MaterialSweepOptions& options = result.options;
  options = given;
  if (options.materials.empty()) options.materials = default_sweep_materials();
  if (options.methods.empty()) options.methods = default_sweep_methods();
  options.check();
  std::vector<sim::Material> materials;
  for (const auto& preset : options.materials) materials.push_back(sim::parse_material(preset));
  const std::size_t methods = options.methods.size();
  std::vector<double> seconds(methods, 0.0), pixels(methods, 0.0);
  result.errors.assign(options.light_counts.size(),
                       std::vector<std::vector<std::vector<double>>>(
                           options.noise.size(), std::vector<std::vector<double>>(
                                                     materials.size(), std::vector<double>(methods, 0.0))));
  for (std::size_t li = 0; li < options.light_counts.size(); ++li) {
    const Eigen::MatrixX3d lights = random_hemisphere_lights(
        options.light_counts[li], std::max(std::cos(rad_from_deg(options.light_cone_deg)), 0.05),
        options.seed);
    for (std::size_t ni = 0; ni < options.noise.size(); ++ni) {
      for (std::size_t mi = 0; mi < materials.size(); ++mi) {
        SyntheticOptions render;
        render.noise = options.noise[ni];
        render.seed = options.seed * 1000003 + mi * 101 + ni;
        const SyntheticScene scene =
            render_synthetic(materials[mi], sweep_grid_size(), sweep_grid_normal, lights, render);
        for (std::size_t k = 0; k < methods; ++k) {
          const auto start = std::chrono::steady_clock::now();
          const SolveResult solved = run_method(options.methods[k], scene.observations, options);
          seconds[k] += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
          pixels[k] += static_cast<double>(scene.observations.pixel_count());
          // Pixels a method could not solve count as 90° (not left out: that would flatter it).
          const AngularErrorStats stats =
              angular_error(solved.normals, scene.truth, scene.observations.mask).stats;
          const double total =
              stats.mean * static_cast<double>(stats.count) + 90.0 * static_cast<double>(stats.missing);
          result.errors[li][ni][mi][k] =
              total / static_cast<double>(std::max<std::size_t>(1, stats.count + stats.missing));
          if (on_cells) on_cells(1);
        }
      }
    }
  }
  for (std::size_t k = 0; k < methods; ++k)
    result.pixels_per_second.push_back(seconds[k] > 0 ? pixels[k] / seconds[k] : 0);
  return result;
}

std::string MaterialSweepResult::summary_table(std::size_t li) const {
  std::string out = fmt::format("{} lights, mean angular error (deg) over {} materials\n{:<14}",
                                options.light_counts[li], options.materials.size(), "");
  for (const auto& m : options.methods) out += fmt::format("{:>12}", m);
  out += "\n";
  for (std::size_t ni = 0; ni < options.noise.size(); ++ni) {
    out += fmt::format("{:<14}", noise_label(options.noise[ni]));
    for (std::size_t k = 0; k < options.methods.size(); ++k) {
      double sum = 0;
      for (const auto& per_material : errors[li][ni]) sum += per_material[k];
      out += fmt::format("{:>12.2f}", sum / static_cast<double>(errors[li][ni].size()));
    }
    out += "\n";
  }
  return out;
}

std::string MaterialSweepResult::material_table(std::size_t li, std::size_t ni) const {
  std::string out = fmt::format("{} lights, {}: angular error (deg) per material\n{:<36}",
                                options.light_counts[li], noise_label(options.noise[ni]), "material");
  for (const auto& m : options.methods) out += fmt::format("{:>12}", m);
  out += "\n";
  for (std::size_t mi = 0; mi < options.materials.size(); ++mi) {
    out += fmt::format("{:<36}", options.materials[mi]);
    for (const double e : errors[li][ni][mi]) out += fmt::format("{:>12.2f}", e);
    out += "\n";
  }
  return out;
}

nlohmann::json MaterialSweepResult::to_json() const {
  nlohmann::json j;
  j["protocol"] =
      "1620 normals (36 azimuths x 45 elevations), random lights over the hemisphere (or within "
      "light_cone_deg of the view axis), values / max, "
      "y + lambda*y*X then 16-bit quantisation (lambda -1: none)";
  j["materials"] = options.materials;
  j["methods"] = options.methods;
  j["light_counts"] = options.light_counts;
  j["noise"] = options.noise;
  j["t_low"] = options.t_low;
  j["light_cone_deg"] = options.light_cone_deg;
  j["azimuth_from"] = options.azimuth_from;
  j["refine_step_deg"] = options.refine_step_deg;
  j["plateau_tolerance"] = options.plateau_tolerance;
  j["falloff"] = options.falloff;
  j["auto_agreement_deg"] = options.auto_agreement_deg;
  j["auto_margin"] = options.auto_margin;
  j["seed"] = options.seed;
  j["threads"] = options.threads;
  j["errors_deg"] = errors;
  j["pixels_per_second"] = pixels_per_second;
  nlohmann::json means = nlohmann::json::array();
  for (std::size_t li = 0; li < errors.size(); ++li) {
    nlohmann::json per_light = nlohmann::json::array();
    for (std::size_t ni = 0; ni < errors[li].size(); ++ni) {
      nlohmann::json row = nlohmann::json::object();
      for (std::size_t k = 0; k < options.methods.size(); ++k) {
        double sum = 0;
        for (const auto& per_material : errors[li][ni]) sum += per_material[k];
        row[options.methods[k]] = sum / static_cast<double>(errors[li][ni].size());
      }
      per_light.push_back(row);
    }
    means.push_back(per_light);
  }
  j["mean_errors_deg"] = means;
  return j;
}

void write_material_plot(const std::filesystem::path& path, const MaterialSweepResult& result, std::size_t li,
                         std::size_t ni) {
  const auto& rows = result.errors[li][ni];
  const auto& methods = result.options.methods;
  const int count = static_cast<int>(rows.size());
  std::vector<int> order(static_cast<std::size_t>(count));
  std::iota(order.begin(), order.end(), 0);
  // Sort by the first bi-polynomial-like column when present, else the first method.
  std::size_t key = 0;
  for (std::size_t k = 0; k < methods.size(); ++k) {
    if (methods[k] == "biquadratic") key = k;
  }
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return rows[static_cast<std::size_t>(a)][key] < rows[static_cast<std::size_t>(b)][key];
  });
  double top = 1;
  for (const auto& r : rows) top = std::max(top, *std::max_element(r.begin(), r.end()));
  top = std::min(top, 30.0);
  const int left = 60, right = 220, upper = 40, bottom = 260, plot_w = std::max(400, 40 * count),
            plot_h = 400;
  cv::Mat image(upper + plot_h + bottom, left + plot_w + right, CV_8UC3, cv::Scalar(255, 255, 255));
  const cv::Scalar black(0, 0, 0), grey(210, 210, 210);
  auto to_y = [&](double e) {
    return upper + plot_h - static_cast<int>(std::lround(std::min(e, top) / top * plot_h));
  };
  auto to_x = [&](int i) { return left + static_cast<int>(std::lround((i + 0.5) * plot_w / count)); };
  for (int t = 0; t <= 5; ++t) {
    const double e = top * t / 5;
    cv::line(image, {left, to_y(e)}, {left + plot_w, to_y(e)}, grey, 1);
    cv::putText(image, fmt::format("{:.1f}", e), {5, to_y(e) + 4}, cv::FONT_HERSHEY_SIMPLEX, 0.4, black, 1);
  }
  cv::rectangle(image, {left, upper}, {left + plot_w, upper + plot_h}, black, 1);
  cv::putText(image,
              fmt::format("mean angular error (deg), {} lights, {}", result.options.light_counts[li],
                          noise_label(result.options.noise[ni])),
              {left, 25}, cv::FONT_HERSHEY_SIMPLEX, 0.55, black, 1);
  static const cv::Scalar palette[] = {{128, 128, 128}, {0, 0, 0},   {200, 0, 200}, {0, 0, 220},
                                       {0, 160, 255},   {0, 160, 0}, {200, 120, 0}, {220, 0, 0}};
  for (std::size_t k = 0; k < methods.size(); ++k) {
    const cv::Scalar colour = palette[k % 8];
    cv::Point previous;
    for (int i = 0; i < count; ++i) {
      const cv::Point point(to_x(i),
                            to_y(rows[static_cast<std::size_t>(order[static_cast<std::size_t>(i)])][k]));
      cv::circle(image, point, 3, colour, cv::FILLED);
      if (i > 0) cv::line(image, previous, point, colour, 1, cv::LINE_AA);
      previous = point;
    }
    const int ly = upper + 20 + 22 * static_cast<int>(k);
    cv::line(image, {left + plot_w + 15, ly - 4}, {left + plot_w + 45, ly - 4}, colour, 2);
    cv::putText(image, methods[k], {left + plot_w + 50, ly}, cv::FONT_HERSHEY_SIMPLEX, 0.45, black, 1);
  }
  for (int i = 0; i < count; ++i) {
    // Material names, rotated: draw on a strip and rotate it.
    const std::string& name =
        result.options.materials[static_cast<std::size_t>(order[static_cast<std::size_t>(i)])];
    cv::Mat strip(20, bottom - 10, CV_8UC3, cv::Scalar(255, 255, 255));
    cv::putText(strip, name, {2, 14}, cv::FONT_HERSHEY_SIMPLEX, 0.35, black, 1);
    cv::Mat rotated;
    cv::rotate(strip, rotated, cv::ROTATE_90_COUNTERCLOCKWISE);
    const int x0 = std::clamp(to_x(i) - 10, 0, image.cols - rotated.cols);
    rotated.copyTo(image(cv::Rect(x0, upper + plot_h + 5, rotated.cols, rotated.rows)));
  }
  io::write_png(path, image);
}

}  // namespace lightstage::pipeline
