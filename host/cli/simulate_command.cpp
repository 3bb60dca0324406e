// `lightstage simulate`: render a stack on the simulated dome, or under
// natural lighting through an uncontrolled camera (for `solve --method
// shape-prior`).
#include "commands.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/common/rig.hpp"
#include "lightstage/host/progress.hpp"
#include "lightstage/pipeline/simulate_folder.hpp"
#include "lightstage/sim/scene_file.hpp"
#include "options.hpp"

#include <fmt/format.h>

#include <chrono>

namespace lightstage::cli {
namespace {

// Flags of --lighting natural.
struct NaturalArgs : pipeline::NaturalSimulation {
  std::string lighting = "dome";
};

// Flags that only one of the two lightings uses: giving one with the other is an error, not ignored.
const std::vector<std::string> kDomeOnlyFlags = {
    "--lights", "--noise",       "--lambda",   "--full-well",       "--read-noise", "--exposure-us",
    "--gain",   "--black-level", "--response", "--no-cast-shadows", "--colour"};
const std::vector<std::string> kNaturalOnlyFlags = {"--frames", "--environment", "--natural-response",
                                                    "--prior-beta"};

void check_lighting_flags(const CLI::App& sub, const NaturalArgs& natural) {
  if (natural.lighting != "dome" && natural.lighting != "natural")
    fail("--lighting: '{}' is neither dome nor natural", natural.lighting);
  const bool is_natural = natural.lighting == "natural";
  for (const auto& flag : is_natural ? kDomeOnlyFlags : kNaturalOnlyFlags) {
    if (sub.count(flag) > 0)
      fail("{} applies to --lighting {} only (this run is --lighting {})", flag,
           is_natural ? "dome" : "natural", natural.lighting);
  }
  if (natural.frames < 1 || natural.frames > 10000)
    fail("--frames: must be in 1..10000, got {}", natural.frames);
  if (natural.prior_beta < 0 || natural.prior_beta > 5)
    fail("--prior-beta: must be 0 (no prior.pfm) or 1..5, got {}", natural.prior_beta);
}

// The `solve` command line that fits a natural-lighting stack.
std::string shape_prior_command(const nlohmann::json& summary) {
  const auto& flags = summary["shape_prior_flags"];
  std::string command =
      fmt::format("lightstage solve --input {} --method shape-prior", summary["stack"].get<std::string>());
  command += flags.contains("prior") ? fmt::format(" --prior {}", flags["prior"].get<std::string>())
                                     : std::string(" --prior DEPTH");
  if (flags.contains("intrinsics"))
    command += fmt::format(" --intrinsics {}", flags["intrinsics"].get<std::string>());
  if (flags.contains("pixel_mm")) command += fmt::format(" --pixel-mm {}", flags["pixel_mm"].get<double>());
  return command + " --out RESULT";
}

}  // namespace

void add_simulate(CLI::App& app) {
  struct Args {
    std::string rig = default_rig_path().string();
    std::string out;
    bool force = false;
    OutputFlags output;
    SimulateArgs sim;
    NaturalArgs natural;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand(
      "simulate",
      "Render an image stack of a simulated object (--scene, --material, --colour) on the simulated dome.\n"
      "\n"
      "--lighting dome (default): one frame per LED of --rig, each LED alone, through the sensor model "
      "(exposure, gain, noise, response, quantisation); light directions and intensities are known, for "
      "`solve` with every method but shape-prior.\n"
      "--lighting natural: --frames images, each under its own random natural lighting (1-3 area lights "
      "plus ambient, or a spherical-harmonic environment: --environment) through an uncontrolled camera "
      "with a random gain and a random nonlinear response per image (--natural-response); no light "
      "directions. Also writes prior.pfm, the true depth degraded to the dissertation's level beta "
      "(--prior-beta), and prints the `solve --method shape-prior` command that fits it.\n"
      "\n"
      "Input: a rig (YAML) and a scene preset or scene file (docs/scene-format.md).\n"
      "Output, in --out (a new or empty folder; --force to write over one): the stack in the DiLiGenT layout "
      "(filenames.txt, 16-bit PNGs, "
      "light_directions.txt, light_intensities.txt, mask.png), ground truth (Normal_gt.png, depth_gt.pfm) "
      "and manifest.json (docs/stack-format.md). Prints one line (or --json, a summary).\n"
      "\n"
      "Examples:\n"
      "  lightstage simulate --scene bumps --material cook-torrance:roughness=0.3 --out out/bumps\n"
      "  lightstage simulate --scene shiny-sphere --colour '{type: patches, saturation: 0.6}' --out out/rgb\n"
      "  lightstage simulate --scene bunny --lighting natural --frames 40 --width 128 --height 128 --out "
      "out/natural");
  sub->add_option("--rig", args->rig, "rig description (YAML)")->capture_default_str();
  sub->add_option("--out", args->out, "output stack folder (new or empty)")->required();
  sub->add_flag("--force", args->force,
                "write into an --out that is not empty: the stack's files replace theirs, nothing else is "
                "removed");
  add_simulate_flags(*sub, args->sim);
  sub->add_option("--colour,--color", args->sim.options.colour,
                  "dome: colour of the diffuse albedo (overrides the scene's `colour`), making RGB frames "
                  "(16-bit PNGs): r,g,b (e.g. 0.9,0.6,0.3), checker, patches, or the scene key's YAML, e.g. "
                  "'{type: patches, period_mm: 16, saturation: 0.6, seed: 3}' or '{type: checker, values: "
                  "[[0.9, 0.3, 0.3], [0.3, 0.3, 0.9]], period_mm: 10}'. Scaled so its BT.601 grey is 1: the "
                  "grey of a frame is the frame without colour. Dichromatic: the diffuse part takes the "
                  "colour, specular highlights and mirrors stay white (docs/scene-format.md)");
  sub->add_option("--lighting", args->natural.lighting,
                  "dome (one LED per frame) or natural (random natural lighting per frame, unknown to the "
                  "solver; for solve --method shape-prior)")
      ->check(CLI::IsMember({"dome", "natural"}))
      ->capture_default_str();
  sub->add_option("--frames", args->natural.frames, "natural: number of images")->capture_default_str();
  sub->add_option("--environment", args->natural.environment,
                  "natural: area-lights (1-3 disks of 3-20 deg plus ambient) or sh (a random second-order "
                  "spherical-harmonic environment)")
      ->check(CLI::IsMember({"area-lights", "sh"}))
      ->capture_default_str();
  sub->add_option("--natural-response", args->natural.response,
                  "natural: random (a random response and gain per image), fixed (one random response, "
                  "auto gain) or linear (identity response, fixed gain)")
      ->check(CLI::IsMember({"random", "fixed", "linear"}))
      ->capture_default_str();
  sub->add_option(
         "--prior-beta", args->natural.prior_beta,
         "natural: write prior.pfm, the true depth quantised and noisy as Fig. 4.5's beta level 1..5 "
         "(higher = coarser); 0 = no prior")
      ->capture_default_str();
  add_output_flags(*sub, args->output, "the stack folder, frames, size and render time");
  sub->callback([args, sub] {
    apply_output_flags(*sub, args->output);
    check_lighting_flags(*sub, args->natural);
    args->sim.resolve();
    const auto start = std::chrono::steady_clock::now();
    nlohmann::json summary;
    if (args->natural.lighting == "natural") {
      Progress progress("simulate", static_cast<std::size_t>(args->natural.frames), "frames",
                        args->output.mode());
      summary = pipeline::simulate_natural_to_folder(
          args->rig, args->sim.options, args->natural, args->out,
          [&progress](std::size_t frames) { progress.advance(frames); }, args->force);
      progress.finish();
    } else {
      const Rig rig = load_rig(args->rig);
      Progress progress("simulate", rig.leds.size(), "frames", args->output.mode());
      summary = pipeline::simulate_to_folder(
          args->rig, args->sim.options, args->out,
          [&progress](std::size_t frames) { progress.advance(frames); }, args->force);
      progress.finish();
      summary["lighting"] = "dome";
    }
    summary["total_seconds"] =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (args->output.json) {
      fmt::print("{}\n", summary.dump());
    } else if (args->output.human()) {
      fmt::print("{} frames of {}x{} ({} lighting) rendered in {:.2f} s -> {}\n",
                 summary["frames"].get<std::size_t>(), summary["width"].get<int>(),
                 summary["height"].get<int>(), summary["lighting"].get<std::string>(),
                 summary["seconds"].get<double>(), args->out);
      if (summary.contains("shape_prior_flags"))
        fmt::print("solve it with: {}\n", shape_prior_command(summary));
    }
  });
}

}  // namespace lightstage::cli
