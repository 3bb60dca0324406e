// `lightstage solve`: normals and albedo from a stack folder.
#include "commands.hpp"
#include "methods.hpp"
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
    SolveCalibration calibration;
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
  sub->add_option("--calibration", args->calibration.file,
                  "light calibration (calibration.json or .lp from `calibrate lights`): its directions and "
                  "intensities replace the stack's, its LED positions give near lights");
  sub->add_flag("--distant-lights", args->calibration.distant,
                "with --calibration: ignore LED positions (one direction per light for every pixel)");
  sub->callback([args] {
    args->solve.resolve();
    const SolveMethod& method = find_solve_method(args->solve.method);
    const auto report = solve_folder(
        args->input, args->solve.radiometry,
        [&](const Observations& observations) { return method.solve(observations, args->solve); }, args->out,
        args->calibration);
    if (args->json) {
      fmt::print("{}\n", report.summary.dump());
    } else if (report.error) {
      print_error_stats(*report.error);
    }
  });
}

}  // namespace lightstage::cli
