// `lightstage solve`: normals and albedo from a stack folder.
#include "commands.hpp"
#include "lightstage/host/progress.hpp"
#include "lightstage/pipeline/solve_folder.hpp"
#include "lightstage/pipeline/solve_methods.hpp"
#include "lightstage/pipeline/solve_tiles.hpp"
#include "options.hpp"

#include <fmt/format.h>

#include <chrono>
#include <memory>

namespace lightstage::cli {
namespace {

// The line that says which shadow threshold the solve used and where it came from.
std::string describe_shadow_threshold(const nlohmann::json& choice, const std::string& method) {
  const ShadowThreshold threshold = ShadowThreshold::from_json(choice);
  if (method == "l2" && !choice.value("used_by_l2", false))
    return "l2 keeps every observation (the published baseline); estimated " + threshold.describe();
  return threshold.describe();
}

}  // namespace

void add_solve(CLI::App& app) {
  struct Args : SolveCommandArgs {
    std::string tile;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand(
      "solve",
      "Estimate surface normals and albedo from an image stack (photometric stereo).\n"
      "\n"
      "Input: a stack folder in the DiLiGenT layout (from `simulate`, `capture` or a public data set; "
      "docs/stack-format.md). Its images are made linear and divided by each light's intensity, then "
      "every pixel inside mask.png is solved by --method (docs/solvers.md).\n"
      "Output, in --out: normal.png (16-bit, value = round((n+1)/2*65535), red = x), normal.exr (float, "
      "R G B = x y z), normal_vis.png, albedo.png/.pfm/.exr, residual.pfm, per-method extras "
      "(confidence.pfm, brdf_*.pfm), summary.json "
      "(method, counts, time, and the angular error when the stack holds Normal_gt.png) and report.html.\n"
      "Prints the angular error against the ground truth when there is one (or --json, summary.json).\n"
      "\n"
      "Example: lightstage solve --input out/stack --method robust --out out/result");
  sub->add_option("--input", args->input, "stack folder")->required();
  sub->add_option("--out", args->out, "output folder")->required();
  add_solve_flags(*sub, args->solve);
  add_solve_calibration_flags(*sub, args->calibration);
  sub->add_option("--tile", args->tile,
                  "solve one capture as independent jobs (docs/large-captures.md): I/N solves tile I of N "
                  "(rows I*H/N to (I+1)*H/N) into OUT/tiles, prepare estimates the shadow threshold the "
                  "jobs share (once, before them), merge writes the solve folder from every tile");
  add_output_flags(*sub, args->output,
                   "summary.json plus out (the folder) and total_seconds (load, solve and write)");
  sub->callback([args, sub] {
    apply_output_flags(*sub, args->output);
    const auto start = std::chrono::steady_clock::now();
    args->solve.resolve();
    std::unique_ptr<Progress> progress;
    const pipeline::ProgressStart start_progress = [&](const pipeline::SolveWork& work) {
      progress = std::make_unique<Progress>("solve " + args->solve.method, work.total, work.unit,
                                            args->output.mode());
      return [p = progress.get()](std::size_t items) { p->advance(items); };
    };
    const auto report =
        args->tile.empty()
            ? pipeline::solve_folder(args->input, args->solve, args->out, args->calibration, start_progress)
            : pipeline::solve_tile(args->input, args->solve, args->out, args->calibration, args->tile,
                                   start_progress);
    if (progress) progress->finish();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (args->output.json) {
      nlohmann::json j = report.summary;
      j["out"] = args->out;
      j["total_seconds"] = seconds;
      fmt::print("{}\n", j.dump());
    } else if (args->output.human() && report.summary.value("tile", nlohmann::json()) == "prepare") {
      fmt::print("{} -> {}\n",
                 describe_shadow_threshold(report.summary["parameters"]["shadow_threshold_choice"],
                                           args->solve.method),
                 report.summary["plan"].get<std::string>());
    } else if (args->output.human() && report.summary.contains("part")) {
      const auto& s = report.summary;
      fmt::print("{}: tile {}/{} (rows {} to {}): solved {} of {} pixels in {:.2f} s -> {}\n",
                 args->solve.method, s["tile"]["index"].get<int>(), s["tile"]["count"].get<int>(),
                 s["tile"]["first_row"].get<int>(),
                 s["tile"]["first_row"].get<int>() + s["tile"]["rows"].get<int>() - 1,
                 s.value("pixels_solved", std::size_t{0}), s.value("pixels_in_mask", std::size_t{0}), seconds,
                 s["part"].get<std::string>());
    } else if (args->output.human()) {
      const auto& s = report.summary;
      fmt::print("{}: solved {} of {} pixels in {:.2f} s -> {}\n", s.value("method", args->solve.method),
                 s.value("pixels_solved", std::size_t{0}), s.value("pixels_in_mask", std::size_t{0}), seconds,
                 args->out);
      if (const auto choice = s["parameters"].find("shadow_threshold_choice");
          choice != s["parameters"].end())
        fmt::print("{}\n", describe_shadow_threshold(*choice, args->solve.method));
      if (report.error) fmt::print("{}\n", report.error->describe());
    }
  });
}

}  // namespace lightstage::cli
