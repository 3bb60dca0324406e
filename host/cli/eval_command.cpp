// `lightstage eval`: angular error of a normal map against ground truth.
#include "commands.hpp"
#include "lightstage/host/eval/angular_error.hpp"

#include <fmt/format.h>

namespace lightstage::cli {

void add_eval(CLI::App& app) {
  struct Args {
    std::string pred;
    std::string gt;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand(
      "eval",
      "Compare a normal map with ground truth.\n"
      "Reads a predicted normal.png and a folder holding Normal_gt.png and mask.png, and prints the mean, "
      "median, 90th-percentile and maximum angular error in degrees over the mask (the DiLiGenT measure).\n"
      "Example: lightstage eval --pred out/result/normal.png --gt out/stack");
  sub->add_option("--pred", args->pred, "predicted normal map (16-bit PNG)")->required();
  sub->add_option("--gt", args->gt, "folder with Normal_gt.png and mask.png")->required();
  sub->add_flag("--json", args->json, "print the statistics as JSON");
  sub->callback([args] {
    const AngularErrorStats stats = evaluate_normal_map(args->pred, args->gt);
    if (args->json) {
      fmt::print("{}\n", stats.to_json().dump());
    } else {
      fmt::print("{}\n", stats.describe());
    }
  });
}

}  // namespace lightstage::cli
