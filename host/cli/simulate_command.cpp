// `lightstage simulate`: render a stack on the simulated dome.
#include "commands.hpp"
#include "options.hpp"
#include "steps.hpp"

#include <fmt/format.h>

namespace lightstage::cli {

void add_simulate(CLI::App& app) {
  struct Args {
    std::string rig = default_rig_path().string();
    std::string out;
    bool json = false;
    SimulateArgs sim;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand(
      "simulate",
      "Render an image stack of a simulated object under a rig's LEDs.\n"
      "One frame per LED through the sensor model, written in the DiLiGenT layout (filenames.txt, 16-bit "
      "PNGs, "
      "light_directions.txt, light_intensities.txt, mask.png) with ground truth (Normal_gt.png, "
      "depth_gt.pfm) "
      "and manifest.json (docs/stack-format.md).\n"
      "Example: lightstage simulate --scene bumps --material cook-torrance:roughness=0.3 --out out/bumps");
  sub->add_option("--rig", args->rig, "rig description (YAML)")->capture_default_str();
  sub->add_option("--out", args->out, "output stack folder")->required();
  sub->add_flag("--json", args->json, "print a JSON summary on stdout");
  add_simulate_flags(*sub, args->sim);
  sub->callback([args] {
    args->sim.resolve();
    const auto summary = simulate_to_folder(args->rig, args->sim.options, args->out);
    if (args->json) fmt::print("{}\n", summary.dump());
  });
}

}  // namespace lightstage::cli
