#include "lightstage/pipeline/reflectometry_folder.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/io/normal_map.hpp"
#include "lightstage/host/io/output_folder.hpp"
#include "lightstage/host/io/stack_io.hpp"

#include <fstream>

namespace lightstage::pipeline {

ReflectometryReport fit_stack_reflectance(const ReflectometrySettings& settings) {
  if (!settings.out.empty()) io::require_separate_output(settings.out, {settings.input});
  const ImageStack stack = io::load_stack(settings.input);
  cv::Mat normals;
  if (!settings.normals.empty()) {
    normals = io::read_normal_map(settings.normals).normals;
  } else if (stack.ground_truth && !stack.ground_truth->normals.empty()) {
    normals = stack.ground_truth->normals;
  } else {
    fail("--normals: {} holds no Normal_gt.png; give a normal map", settings.input.string());
  }
  RadiometryOptions radiometry;
  radiometry.clamp_to_one = settings.clamp_to_one;
  const Observations observations = make_observations(stack, radiometry);
  const ReflectanceSamples samples = collect_samples(observations, normals, settings.samples);
  ReflectometryReport report;
  report.samples = samples.size();
  report.fits = {fit_lambert(samples), fit_bipolynomial_model(samples, 1), fit_bipolynomial_model(samples, 2),
                 fit_bipolynomial_model(samples, 3), fit_cook_torrance(samples)};
  report.json = {{"input", settings.input.string()},
                 {"samples", samples.size()},
                 {"t_low", settings.samples.t_low},
                 {"shadow_threshold", settings.samples.shadow_threshold},
                 {"fits", nlohmann::json::array()}};
  for (const auto& fit : report.fits) report.json["fits"].push_back(fit.to_json());
  if (!settings.out.empty()) {
    std::filesystem::create_directories(settings.out);
    const std::filesystem::path file = settings.out / "reflectance.json";
    std::ofstream stream(file);
    stream << report.json.dump(2) << "\n";
    if (!stream) fail("{}: cannot write", file.string());
  }
  return report;
}

}  // namespace lightstage::pipeline
