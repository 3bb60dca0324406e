// Extends the installed library from outside: registers a solve method of its
// own (the registry's extension point), solves a synthetic Lambertian sweep
// with it and checks the normals against the truth. Prints the version and the
// error; exits non-zero when the solve is wrong.
#include "lightstage/common/geometry.hpp"
#include "lightstage/common/version.hpp"
#include "lightstage/host/eval/angular_error.hpp"
#include "lightstage/pipeline/solve_methods.hpp"
#include "lightstage/pipeline/synthetic_observations.hpp"
#include "lightstage/sim/material.hpp"

#include <cstdio>

namespace pipeline = lightstage::pipeline;

int main() {
  int calls = 0;
  // A copy: registering a method may move the registry's entries.
  const pipeline::SolveFunction l2 = pipeline::find_solve_method("l2").solve;
  pipeline::register_solve_method(
      {"consumer-l2", "l2, counted by the consumer",
       [&](const lightstage::Observations& observations, const pipeline::SolveSettings& settings) {
         ++calls;
         return l2(observations, settings);
       }});
  pipeline::SyntheticOptions options;
  options.scale = 0.5;
  // Normals within 30° of the view, lights within 45° of it: every light
  // lights every pixel, where plain least squares is exact.
  const auto normal_at = [](int x, int y) {
    return lightstage::direction_from_elevation_azimuth(lightstage::rad_from_deg(60 + 2.0 * y),
                                                        lightstage::rad_from_deg(20.0 * x));
  };
  const pipeline::SyntheticScene scene =
      pipeline::render_synthetic(lightstage::sim::parse_material("lambert"), cv::Size(18, 15), normal_at,
                                 pipeline::random_hemisphere_lights(40, 0.71, 7), options);
  pipeline::SolveSettings settings;
  settings.method = "consumer-l2";
  settings.resolve();
  const lightstage::SolveResult result = pipeline::solve_with(scene.observations, settings);
  const lightstage::AngularErrorStats error = lightstage::angular_error(result.normals, scene.truth).stats;
  std::printf("lightstage %s: %zu methods, consumer-l2 called %d time(s), %s\n", lightstage::kVersion,
              pipeline::solve_methods().size(), calls, error.describe().c_str());
  const bool ok = calls == 1 && error.count == scene.observations.pixel_count() && error.mean < 0.01;
  return ok ? 0 : 1;
}
