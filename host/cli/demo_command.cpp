// `lightstage demo`: the main job end to end on the simulated dome.
#include "commands.hpp"
#include "options.hpp"
#include "steps.hpp"

#include <fmt/format.h>

namespace lightstage::cli {

void add_demo(CLI::App& app) {
  struct Args {
    std::string rig = default_rig_path().string();
    std::string out = "out/demo";
    double shadow_threshold = 0.02;
    SimulateArgs sim;
  };
  auto args = std::make_shared<Args>();
  // The l2 solver assumes distant lights; near-light solving needs calibrated
  // LED positions, so the demo's default world matches the solver's model.
  args->sim.light_model = "distant";
  CLI::App* sub =
      app.add_subcommand("demo",
                         "Run the pipeline end to end on the simulated dome.\n"
                         "Simulates a stack under the rig's LEDs (OUT/stack), solves it with Lambertian "
                         "least squares and a shadow "
                         "threshold (OUT/result), and prints the angular error against the ground truth.\n"
                         "Example: lightstage demo --out out/demo --scene bumps");
  sub->add_option("--rig", args->rig, "rig description (YAML)")->capture_default_str();
  sub->add_option("--out", args->out, "output folder")->capture_default_str();
  sub->add_option("--shadow-threshold", args->shadow_threshold, "solver shadow threshold")
      ->capture_default_str();
  add_simulate_flags(*sub, args->sim);
  sub->callback([args] {
    args->sim.resolve();
    const std::filesystem::path out = args->out;
    const auto simulated = simulate_to_folder(args->rig, args->sim.options, out / "stack");
    fmt::print("simulated {} frames ({}x{}) of '{}' under {} -> {}\n", simulated["frames"].get<int>(),
               simulated["width"].get<int>(), simulated["height"].get<int>(), args->sim.options.scene,
               args->rig, (out / "stack").string());
    L2Options l2;
    l2.shadow_threshold = args->shadow_threshold;
    const auto report = solve_folder(out / "stack", RadiometryOptions{}, l2, out / "result");
    const auto& summary = report.summary;
    fmt::print("solved {} of {} pixels with l2 (shadow threshold {}) in {:.2f} s -> {}\n",
               summary["pixels_solved"].get<std::size_t>(), summary["pixels_in_mask"].get<std::size_t>(),
               l2.shadow_threshold, summary["seconds"].get<double>(), (out / "result").string());
    if (report.error) print_error_stats(*report.error);
    if (std::filesystem::exists(out / "result" / "report.html"))
      fmt::print("report (open in a browser) -> {}\n", (out / "result" / "report.html").string());
  });
}

}  // namespace lightstage::cli
