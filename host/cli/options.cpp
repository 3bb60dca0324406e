#include "options.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/pipeline/solve_methods.hpp"
#include "lightstage/sim/scene_file.hpp"
#include "shape_prior_args.hpp"

#include <fmt/format.h>

namespace lightstage::cli {

void add_output_flags(CLI::App& sub, OutputFlags& flags, const std::string& json_what) {
  sub.add_flag("--quiet,-q", flags.quiet, "print nothing but errors (no progress line, no result text)");
  sub.add_flag("--json", flags.json, "print one JSON object on stdout and nothing else there: " + json_what);
}

void apply_output_flags(const CLI::App& sub, const OutputFlags& flags) {
  const CLI::App* root = &sub;
  while (root->get_parent() != nullptr) root = root->get_parent();
  if (root->count("--log-level") > 0) return;  // asked for explicitly
  if (flags.quiet) {
    set_log_level("error");
  } else if (flags.json) {
    set_log_level("warn");
  }
}

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
  sub.add_option(
         "--seed", o.seed,
         "random seed: sensor noise (simulate --lighting natural: also the lightings, responses, gains "
         "and the prior's noise)")
      ->capture_default_str();
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

void add_solve_flags(CLI::App& sub, pipeline::SolveSettings& args) {
  std::string methods;
  for (const auto& method : pipeline::solve_methods())
    methods += fmt::format("\n  {}: {}", method.name, method.help);
  sub.add_option("--method", args.method, "solver (docs/solvers.md):" + methods)
      ->check(CLI::IsMember(pipeline::solve_method_names()))
      ->capture_default_str();
  sub.add_option(
      "--shadow-threshold", args.shadow_threshold,
      "drop observations at or below T (values after division by full scale and light intensity); "
      "l2: -1 (default) keeps all; other methods: default estimated from the stack (its dark frames or "
      "black level and the noise floor of its darkest observations; summary.json "
      "parameters.shadow_threshold_choice)");
  sub.add_option("--t-low", args.t_low,
                 "keep the lowest fraction F of each pixel's remaining observations (default: l2 1, robust "
                 "0.5, bi-polynomial and auto 0.25)");
  sub.add_option("--min-observations", args.min_observations,
                 "reject pixels with fewer observations (l2, robust, monotonic, rpca, l1, sbl)");
  sub.add_option("--max-iterations", args.max_iterations, "bi-polynomial alternations (default 100)");
  sub.add_option("--memory-limit", args.memory_limit,
                 "memory the solve may take: auto (half the machine's), bytes, or with K, M, G: 1.5G. A "
                 "stack that needs more is read and solved in row bands (every method but shape-prior; "
                 "docs/large-captures.md)")
      ->capture_default_str();
  sub.add_option("--falloff", args.falloff,
                 "bi-polynomial and auto: the start's incidence fall-off kappa, rho ~ 1 + kappa n.l: 'auto' "
                 "estimates it from the object, 0 is the Lambertian start as published (DiLiGenT ball: "
                 "biquadratic 2.21 deg with 0, 1.23 with auto)")
      ->capture_default_str();
  sub.add_option("--estimator", args.estimator, "robust: irls-l1, ransac (locally optimised) or none")
      ->check(CLI::IsMember({"irls-l1", "ransac", "none"}))
      ->capture_default_str();
  sub.add_flag("--shadow-screen", args.shadow_screen,
               "robust: drop values far below a RANSAC consensus before T_low (cast shadows the shadow "
               "threshold does not catch)");
  sub.add_option("--azimuth-from", args.azimuth_from,
                 "monotonic: azimuth from isotropy (Alldrin-Kriegman) or from another method's normals "
                 "(l2, robust, bilinear, biquadratic, bicubic, ...)")
      ->capture_default_str();
  sub.add_option("--gamma", args.monotonic.gamma, "monotonic: y' <- y'^gamma before the cost")
      ->capture_default_str();
  sub.add_option("--plateau-tolerance", args.monotonic.plateau_tolerance,
                 "monotonic and auto: take the lowest elevation whose cost is within (1 + T) x the minimum "
                 "(0 = the plain minimum, as published)")
      ->capture_default_str();
  sub.add_flag("--no-clamp", args.no_clamp, "do not clamp normalised values to <= 1");
  sub.add_option("--threads", args.threads,
                 "threads for every stage: decoding, solving, writing and the report (0 = all cores)");
  sub.add_option("--crop", args.crop,
                 "X,Y,W,H: read and solve only this region of the images (pixels from the top left); near "
                 "lights and calibration stay placed in the whole image");
  add_shape_prior_flags(sub, args.shape_prior);
}

void add_solve_calibration_flags(CLI::App& sub, pipeline::SolveCalibration& calibration) {
  sub.add_option("--calibration", calibration.file,
                 "light calibration (calibration.json or .lp from `calibrate lights`): its directions and "
                 "intensities replace the stack's, its LED positions give near lights");
  sub.add_flag(
      "--distant-lights", calibration.distant,
      "ignore LED positions of the calibration or the stack (one direction per light for every pixel)");
  sub.add_option("--response", calibration.response,
                 "camera response (from `lightstage camera response`) to linearise the frames with; default: "
                 "the one the stack's manifest records")
      ->check(CLI::ExistingFile);
}

}  // namespace lightstage::cli
