#include "options.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/sim/scene_file.hpp"

#include <fmt/format.h>

namespace lightstage::cli {

void SimulateArgs::resolve() {
  options.light_model = sim::parse_light_model(light_model);
  if (noise == "none") {
    options.sensor.noise = sim::NoiseModel::kNone;
  } else if (noise == "physical") {
    options.sensor.noise = sim::NoiseModel::kPhysical;
  } else if (noise == "signal-dependent") {
    options.sensor.noise = sim::NoiseModel::kSignalDependent;
    if (!(options.sensor.lambda > 0))
      fail("--noise signal-dependent needs --lambda > 0 (the dissertation uses 0.05-0.3)");
  } else {
    fail("--noise: unknown model '{}' (none, physical, signal-dependent)", noise);
  }
  options.sensor.response = sim::ResponseCurve::parse(response);
  if (no_cast_shadows) options.cast_shadows = false;
  options.check();
}

void add_simulate_flags(CLI::App& sub, SimulateArgs& args) {
  auto& o = args.options;
  sub.add_option("--scene", o.scene,
                 fmt::format("scene preset ({}) or a scene YAML file (docs/scene-format.md)",
                             fmt::join(sim::scene_presets(), ", ")))
      ->capture_default_str();
  sub.add_option("--material", o.material,
                 "material preset overriding the scene's, e.g. lambert, "
                 "cook-torrance:roughness=0.3,ks=0.5, two-lobe-fabric");
  sub.add_option("--lights", args.light_model, "near (LEDs as point lights with 1/d^2 falloff) or distant")
      ->capture_default_str();
  sub.add_option("--width", o.width, "image width (keeps the rig camera's field of view)");
  sub.add_option("--height", o.height, "image height");
  sub.add_option("--seed", o.seed, "noise seed")->capture_default_str();
  sub.add_option("--noise", args.noise, "none, physical (shot + read) or signal-dependent (y + lambda*y*X)")
      ->capture_default_str();
  sub.add_option("--lambda", o.sensor.lambda, "lambda of the signal-dependent noise")->capture_default_str();
  sub.add_option("--full-well", o.sensor.full_well_e, "physical noise: electrons at full scale")
      ->capture_default_str();
  sub.add_option("--read-noise", o.sensor.read_noise_e, "physical noise: read noise, electrons")
      ->capture_default_str();
  sub.add_option("--bit-depth", o.sensor.bit_depth, "8..16 (default: the rig camera's)");
  sub.add_option("--exposure-us", o.sensor.exposure_us, "exposure (default: the rig camera's)");
  sub.add_option("--gain", o.sensor.gain, "analogue gain (default: the rig camera's)");
  sub.add_option("--black-level", o.sensor.black_level, "black level in 16-bit DN")->capture_default_str();
  sub.add_option("--response", args.response, "response curve: identity, gamma:2.2, srgb, s-curve:2")
      ->capture_default_str();
  sub.add_flag("--no-cast-shadows", args.no_cast_shadows, "attached shadows only");
  sub.add_option("--threads", o.threads, "render threads (0 = all cores)")->capture_default_str();
}

void add_solve_flags(CLI::App& sub, SolveArgs& args) {
  sub.add_option("--method", args.method, "solver: l2 (Lambertian least squares)")
      ->check(CLI::IsMember({"l2"}))
      ->capture_default_str();
  sub.add_option("--shadow-threshold", args.l2.shadow_threshold,
                 "drop observations at or below T (values after division by full scale and light intensity); "
                 "-1 keeps all")
      ->capture_default_str();
  sub.add_option("--t-low", args.l2.t_low,
                 "keep the lowest fraction F of each pixel's remaining observations")
      ->capture_default_str();
  sub.add_option("--min-observations", args.l2.min_observations, "reject pixels with fewer observations")
      ->capture_default_str();
  sub.add_flag("--no-clamp", args.no_clamp, "do not clamp normalised values to <= 1");
  sub.add_option("--threads", args.l2.threads, "solver threads (0 = all cores)")->capture_default_str();
}

}  // namespace lightstage::cli
