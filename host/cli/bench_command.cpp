// `lightstage bench materials`: the dissertation's material sweep (Table 3.2's shape).
#include "commands.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "material_sweep.hpp"

#include <fmt/format.h>

#include <fstream>
#include <sstream>

namespace lightstage::cli {
namespace {

std::vector<double> parse_noise_list(const std::vector<std::string>& items) {
  std::vector<double> out;
  for (const auto& item : items) {
    if (item == "none") {
      out.push_back(-1);
      continue;
    }
    try {
      std::size_t used = 0;
      out.push_back(std::stod(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      fail("--noise: '{}' is not a number or 'none'", item);
    }
  }
  return out;
}

}  // namespace

void add_bench(CLI::App& app) {
  CLI::App* bench =
      app.add_subcommand("bench", "Measurements that reproduce the dissertation's experiments.");
  bench->require_subcommand(1);
  struct Args {
    MaterialSweepOptions sweep;
    std::vector<std::string> noise = {"none", "0", "0.05", "0.15", "0.3"};
    std::string out;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = bench->add_subcommand(
      "materials",
      "The material sweep: 1620 normals, random hemisphere lights, BRDF families (Cook-Torrance roughness, "
      "Ward, Blinn-Phong, Oren-Nayar, the Fig. 2.8 two-lobe families), noise y + lambda*y*X with 16-bit "
      "quantisation; every solver method on the same data. Prints Table 3.2's shape (rows = noise, columns = "
      "methods, mean over materials) and a per-material table; with --out writes materials.json and a "
      "per-material error plot materials.png.\n"
      "Example: lightstage bench materials --lights 100 --noise none,0,0.05,0.15,0.3 --out out/sweep");
  sub->add_option("--lights", args->sweep.light_counts, "light counts, e.g. 25,50,100,200")
      ->delimiter(',')
      ->capture_default_str();
  sub->add_option("--noise", args->noise, "noise levels lambda ('none' = double precision)")
      ->delimiter(',')
      ->capture_default_str();
  sub->add_option("--materials", args->sweep.materials, "material presets (default: the built-in sweep)")
      ->delimiter(';');
  sub->add_option("--methods", args->sweep.methods,
                  "methods (solve --method names, plus lambert-low = l2 on the lowest T_low)")
      ->delimiter(',');
  sub->add_option("--t-low", args->sweep.t_low, "T_low of the bi-polynomial methods")->capture_default_str();
  sub->add_option("--azimuth-from", args->sweep.azimuth_from, "monotonic: isotropy or a method's normals")
      ->capture_default_str();
  sub->add_option("--refine-step", args->sweep.refine_step_deg, "monotonic: 2-D refinement step (0 = off)")
      ->capture_default_str();
  sub->add_option("--auto-agreement", args->sweep.auto_agreement_deg,
                  "auto: answers closer than this are averaged")
      ->capture_default_str();
  sub->add_option("--auto-margin", args->sweep.auto_margin, "auto: monotonicity margin to prefer monotonic")
      ->capture_default_str();
  sub->add_option("--seed", args->sweep.seed, "lights and noise seed")->capture_default_str();
  sub->add_option("--threads", args->sweep.threads, "solver threads")->capture_default_str();
  sub->add_option("--out", args->out, "folder for materials.json and materials.png");
  sub->add_flag("--json", args->json, "print the JSON result on stdout");
  sub->callback([args] {
    args->sweep.noise = parse_noise_list(args->noise);
    const MaterialSweepResult result = run_material_sweep(args->sweep);
    if (args->json) {
      fmt::print("{}\n", result.to_json().dump());
    } else {
      for (std::size_t li = 0; li < result.options.light_counts.size(); ++li) {
        fmt::print("{}\n", result.summary_table(li));
        fmt::print("{}\n", result.material_table(li, 0));
      }
      fmt::print("pixels/s ({} threads):", result.options.threads);
      for (std::size_t k = 0; k < result.options.methods.size(); ++k)
        fmt::print(" {} {:.0f};", result.options.methods[k], result.pixels_per_second[k]);
      fmt::print("\n");
    }
    if (!args->out.empty()) {
      const std::filesystem::path out = args->out;
      std::filesystem::create_directories(out);
      std::ofstream(out / "materials.json") << result.to_json().dump(2) << "\n";
      write_material_plot(out / "materials.png", result, 0, 0);
      logger("host")->info("wrote {} and {}", (out / "materials.json").string(),
                           (out / "materials.png").string());
    }
  });
}

}  // namespace lightstage::cli
