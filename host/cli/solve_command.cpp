// `lightstage solve`: normals and albedo from a stack folder.
#include "commands.hpp"
#include "lightstage/host/progress.hpp"
#include "lightstage/pipeline/solve_folder.hpp"
#include "lightstage/pipeline/solve_methods.hpp"
#include "options.hpp"

#include <fmt/format.h>

#include <chrono>
#include <memory>

namespace lightstage::cli {
namespace {

// The line that says which shadow threshold the solve used and where it came from.
std::string describe_shadow_threshold(const nlohmann::json& choice, const std::string& method) {
  ShadowThreshold threshold;
  threshold.value = choice.value("value", 0.0);
  threshold.source = choice.value("source", std::string{});
  threshold.level = choice.value("level", 0.0);
  threshold.noise = choice.value("noise", 0.0);
  if (method == "l2" && !choice.value("used_by_l2", false))
    return "l2 keeps every observation (the published baseline); estimated " + threshold.describe();
  return threshold.describe();
}

}  // namespace

void add_solve(CLI::App& app) {
  struct Args {
    std::string input;
    std::string out;
    OutputFlags output;
    pipeline::SolveSettings solve;
    pipeline::SolveCalibration calibration;
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
  sub->add_option("--calibration", args->calibration.file,
                  "light calibration (calibration.json or .lp from `calibrate lights`): its directions and "
                  "intensities replace the stack's, its LED positions give near lights");
  sub->add_flag(
      "--distant-lights", args->calibration.distant,
      "ignore LED positions of the calibration or the stack (one direction per light for every pixel)");
  sub->add_option(
         "--response", args->calibration.response,
         "camera response (from `lightstage camera response`) to linearise the frames with; default: "
         "the one the stack's manifest records")
      ->check(CLI::ExistingFile);
  add_output_flags(*sub, args->output,
                   "summary.json plus out (the folder) and total_seconds (load, solve and write)");
  sub->callback([args, sub] {
    apply_output_flags(*sub, args->output);
    const auto start = std::chrono::steady_clock::now();
    args->solve.resolve();
    std::unique_ptr<Progress> progress;
    const auto report = pipeline::solve_folder(
        args->input, args->solve, args->out, args->calibration, [&](const pipeline::SolveWork& work) {
          progress = std::make_unique<Progress>("solve " + args->solve.method, work.total, work.unit,
                                                args->output.mode());
          return [p = progress.get()](std::size_t items) { p->advance(items); };
        });
    if (progress) progress->finish();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (args->output.json) {
      nlohmann::json j = report.summary;
      j["out"] = args->out;
      j["total_seconds"] = seconds;
      fmt::print("{}\n", j.dump());
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
