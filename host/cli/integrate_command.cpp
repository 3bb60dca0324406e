// `lightstage integrate`: depth and a mesh from a normal map (and optionally
// a depth prior to fuse with).
#include "commands.hpp"

#include "lightstage/host/progress.hpp"
#include "lightstage/pipeline/integrate_folder.hpp"
#include "options.hpp"

#include <fmt/format.h>

#include <chrono>
#include <cmath>

namespace lightstage::cli {
namespace {

struct IntegrateArgs : pipeline::IntegrateSettings {
  OutputFlags output;
};

// The progress line shows the share of the linear solves done (per mille).
constexpr std::size_t kProgressSteps = 1000;

void run(const IntegrateArgs& a) {
  const auto start = std::chrono::steady_clock::now();
  Progress progress(a.prior.empty() ? "integrate" : "fuse", kProgressSteps, "", a.output.mode());
  const pipeline::IntegrateReport report = pipeline::integrate_folder(a, [&progress](double fraction) {
    progress.advance_to(static_cast<std::size_t>(std::lround(fraction * kProgressSteps)));
  });
  progress.finish();
  if (a.output.json) {
    nlohmann::json j = report.summary;
    j["out"] = a.out;
    j["total_seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    fmt::print("{}\n", j.dump());
  } else if (a.output.human()) {
    fmt::print("surface of {} pixels in {:.2f} s ({} solver iterations) -> {}\n", report.stats.pixels,
               report.stats.seconds, report.stats.solver_iterations, a.out);
  }
}

}  // namespace

void add_integrate(CLI::App& app) {
  auto args = std::make_shared<IntegrateArgs>();
  CLI::App* sub = app.add_subcommand(
      "integrate",
      "Depth and a mesh from a normal map (docs/surfaces.md).\n"
      "\n"
      "Integrates the normals over the mask (Poisson least squares, or Frankot-Chellappa for full "
      "rectangles), or with --prior fuses them with a coarse depth map (dissertation Eq. 4.9).\n"
      "Input: a `solve` result folder (--input: normal.png, albedo.png for the mesh colours) or a normal "
      "map (--normals, 16-bit PNG in the project encoding); optionally a mask, a depth prior and the "
      "camera (--intrinsics for perspective, else orthographic with --pixel-mm).\n"
      "Output, in --out: depth.pfm (orthographic: height toward the camera in --pixel-mm units, pixels by "
      "default, up to an additive constant; perspective: distance along the axis, up to scale), depth.exr "
      "(the same, float channel Z), depth.png, "
      "mesh.ply / mesh.obj and surface.json. Prints one line (or --json, surface.json).\n"
      "\n"
      "Example: lightstage integrate --input out/result --mask out/stack/mask.png --out out/surface --mesh "
      "both");
  sub->add_option("--input", args->input, "a solve result folder (normal.png, albedo.png)");
  sub->add_option("--normals", args->normals, "normal map (16-bit PNG, project encoding)");
  sub->add_option("--mask", args->mask, "object mask (default: where the normal map has normals)");
  sub->add_option("--albedo", args->albedo, "albedo image for the mesh colours (grey or colour PNG or PFM)");
  sub->add_option("--out", args->out, "output folder")->required();
  sub->add_option("--method", args->method, "poisson or frankot-chellappa")
      ->check(CLI::IsMember({"poisson", "frankot-chellappa", "fc"}))
      ->capture_default_str();
  sub->add_flag("--preserve-discontinuities", args->integration.preserve_discontinuities,
                "reweight where the normals disagree with any smooth surface (depth jumps)");
  sub->add_option("--intrinsics", args->intrinsics, "3x3 intrinsics (K.txt): perspective camera");
  sub->add_option("--pixel-mm", args->pixel_mm,
                  "orthographic: pixel size (mm) at the object; 1 = pixel units")
      ->capture_default_str();
  sub->add_option("--mean-depth", args->mean_depth,
                  "perspective without a prior: scale the result to this mean depth")
      ->capture_default_str();
  sub->add_option("--prior", args->prior, "depth prior to fuse with (16-bit PNG, PFM or PLY)");
  sub->add_option("--prior-png-scale", args->prior_png_scale, "depth unit per DN of a 16-bit PNG prior")
      ->capture_default_str();
  sub->add_option("--lambda", args->fusion.lambda, "fusion: weight of the prior's depth rows (Eq. 4.9)")
      ->capture_default_str();
  sub->add_option("--mesh", args->mesh, "mesh files: ply, obj, both or none")
      ->check(CLI::IsMember({"ply", "obj", "both", "none"}))
      ->capture_default_str();
  sub->add_option("--mesh-step", args->mesh_step,
                  "one mesh vertex every N pixels each way; auto: every pixel, or as few as keep the mesh "
                  "near 4 million vertices")
      ->capture_default_str();
  add_output_flags(*sub, args->output, "surface.json plus out (the folder) and total_seconds");
  sub->callback([args, sub] {
    apply_output_flags(*sub, args->output);
    run(*args);
  });
}

}  // namespace lightstage::cli
