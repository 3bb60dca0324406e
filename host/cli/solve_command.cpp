// `lightstage solve`: normals and albedo from a stack folder.
#include "commands.hpp"
#include "options.hpp"
#include "steps.hpp"

#include <fmt/format.h>

namespace lightstage::cli {

void add_solve(CLI::App& app) {
  struct Args {
    std::string input;
    std::string out;
    bool json = false;
    SolveArgs solve;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand(
      "solve",
      "Estimate surface normals and albedo from an image stack.\n"
      "Reads a stack folder (DiLiGenT layout, e.g. from `simulate` or a public dataset), converts it to "
      "linear "
      "values divided by each light's intensity, and solves per pixel. Writes normal.png (16-bit, "
      "value = round((n+1)/2*65535), red = x), normal_vis.png, albedo.png/.pfm, residual.pfm and "
      "summary.json "
      "(with the angular error when the stack holds Normal_gt.png).\n"
      "Example: lightstage solve --input out/stack --method l2 --shadow-threshold 0.02 --out out/result");
  sub->add_option("--input", args->input, "stack folder")->required();
  sub->add_option("--out", args->out, "output folder")->required();
  sub->add_flag("--json", args->json, "print summary.json on stdout");
  add_solve_flags(*sub, args->solve);
  sub->callback([args] {
    args->solve.resolve();
    const auto report = solve_folder(args->input, args->solve.radiometry, args->solve.l2, args->out);
    if (args->json) {
      fmt::print("{}\n", report.summary.dump());
    } else if (report.error) {
      print_error_stats(*report.error);
    }
  });
}

}  // namespace lightstage::cli
