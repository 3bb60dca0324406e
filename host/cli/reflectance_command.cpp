// `lightstage reflectance`: fit reflectance models to a stack with known normals.
#include "commands.hpp"
#include "lightstage/pipeline/reflectometry_folder.hpp"

#include <fmt/format.h>

namespace lightstage::cli {

void add_reflectance(CLI::App& app) {
  struct Args {
    std::string input;
    std::string normals;
    std::string out;
    SampleOptions samples;
    bool no_clamp = false;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand(
      "reflectance",
      "Fit reflectance models to a stack whose normals are known (reflectometry, dissertation 3.5).\n"
      "One BRDF for the whole object: Lambert, bilinear, biquadratic, bicubic (bi-polynomial, linear least "
      "squares) and Cook-Torrance (kd + ks * lobe, roughness and f0 on a grid), each fitted to every lit "
      "observation (or the lowest --t-low per pixel). Prints RMSE / MAE per model; --out writes "
      "reflectance.json with the parameters.\n"
      "Example: lightstage reflectance --input data/diligent/ballPNG --t-low 0.5");
  sub->add_option("--input", args->input, "stack folder")->required();
  sub->add_option("--normals", args->normals, "normal map (16-bit PNG); default: the stack's Normal_gt.png");
  sub->add_option("--shadow-threshold", args->samples.shadow_threshold, "drop values at or below T")
      ->capture_default_str();
  sub->add_option("--t-low", args->samples.t_low, "per pixel, keep the lowest fraction of lit observations")
      ->capture_default_str();
  sub->add_flag("--no-clamp", args->no_clamp, "do not clamp normalised values to <= 1");
  sub->add_option("--out", args->out, "folder for reflectance.json");
  sub->add_flag("--json", args->json, "print the JSON result on stdout");
  sub->callback([args] {
    pipeline::ReflectometrySettings settings;
    settings.input = args->input;
    settings.normals = args->normals;
    settings.samples = args->samples;
    settings.clamp_to_one = !args->no_clamp;
    settings.out = args->out;
    const pipeline::ReflectometryReport report = pipeline::fit_stack_reflectance(settings);
    const nlohmann::json& result = report.json;
    const auto& fits = report.fits;
    if (args->json) {
      fmt::print("{}\n", result.dump());
    } else {
      fmt::print("{} samples; fit errors of rho*(n.l) against the values:\n{:<14}{:>12}{:>12}{:>14}\n",
                 report.samples, "model", "RMSE", "MAE", "RMSE / mean");
      for (const auto& fit : fits)
        fmt::print("{:<14}{:>12.5f}{:>12.5f}{:>14.4f}\n", fit.model, fit.rmse, fit.mae, fit.relative_rmse);
    }
  });
}

}  // namespace lightstage::cli
