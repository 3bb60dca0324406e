// `lightstage reflectance`: fit reflectance models to a stack with known normals.
#include <fstream>
#include "commands.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/host/io/normal_map.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/host/reflectance/reflectometry.hpp"

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
    const ImageStack stack = io::load_stack(args->input);
    cv::Mat normals;
    if (!args->normals.empty()) {
      normals = io::read_normal_map(args->normals).normals;
    } else if (stack.ground_truth && !stack.ground_truth->normals.empty()) {
      normals = stack.ground_truth->normals;
    } else {
      fail("--normals: {} holds no Normal_gt.png; give a normal map", args->input);
    }
    RadiometryOptions radiometry;
    radiometry.clamp_to_one = !args->no_clamp;
    const Observations observations = make_observations(stack, radiometry);
    const ReflectanceSamples samples = collect_samples(observations, normals, args->samples);
    std::vector<ReflectanceFit> fits = {fit_lambert(samples), fit_bipolynomial_model(samples, 1),
                                        fit_bipolynomial_model(samples, 2),
                                        fit_bipolynomial_model(samples, 3), fit_cook_torrance(samples)};
    nlohmann::json result = {{"input", args->input},
                             {"samples", samples.size()},
                             {"t_low", args->samples.t_low},
                             {"shadow_threshold", args->samples.shadow_threshold},
                             {"fits", nlohmann::json::array()}};
    for (const auto& fit : fits) result["fits"].push_back(fit.to_json());
    if (args->json) {
      fmt::print("{}\n", result.dump());
    } else {
      fmt::print("{} samples; fit errors of rho*(n.l) against the values:\n{:<14}{:>12}{:>12}{:>14}\n",
                 samples.size(), "model", "RMSE", "MAE", "RMSE / mean");
      for (const auto& fit : fits)
        fmt::print("{:<14}{:>12.5f}{:>12.5f}{:>14.4f}\n", fit.model, fit.rmse, fit.mae, fit.relative_rmse);
    }
    if (!args->out.empty()) {
      std::filesystem::create_directories(args->out);
      std::ofstream(std::filesystem::path(args->out) / "reflectance.json") << result.dump(2) << "\n";
    }
  });
}

}  // namespace lightstage::cli
