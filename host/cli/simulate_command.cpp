// `lightstage simulate`: render a stack on the simulated dome, or under
// natural lighting through an uncontrolled camera (for `solve --method
// shape-prior`).
#include "commands.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/common/rig.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/host/progress.hpp"
#include "lightstage/sim/natural_capture.hpp"
#include "lightstage/sim/scene_file.hpp"
#include "options.hpp"
#include "steps.hpp"

#include <fmt/format.h>

#include <chrono>
#include <fstream>

namespace lightstage::cli {
namespace {

// Flags of --lighting natural.
struct NaturalArgs {
  std::string lighting = "dome";
  std::string environment = "area-lights";
  std::string response = "random";
  int frames = sim::NaturalLightingOptions{}.images;
  int prior_beta = 3;
};

// Flags that only one of the two lightings uses: giving one with the other is an error, not ignored.
const std::vector<std::string> kDomeOnlyFlags = {
    "--lights",      "--noise", "--lambda",      "--full-well", "--read-noise",
    "--exposure-us", "--gain",  "--black-level", "--response",  "--no-cast-shadows"};
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

sim::NaturalLightingKind parse_environment(const std::string& text) {
  if (text == "area-lights") return sim::NaturalLightingKind::kAreaLights;
  if (text == "sh") return sim::NaturalLightingKind::kSphericalHarmonics;
  fail("--environment: '{}' is neither area-lights nor sh", text);
}

// Renders the scene under natural lighting (natural_capture.hpp) and writes the
// stack, a degraded depth prior and, for a pinhole camera, its intrinsics.
nlohmann::json simulate_natural_to_folder(const std::filesystem::path& rig_path,
                                          const sim::SimulateOptions& options, const NaturalArgs& args,
                                          const std::filesystem::path& out, OutputMode mode) {
  options.check();
  const Rig rig = load_rig(rig_path);
  sim::NaturalCaptureOptions capture;
  capture.lighting.kind = parse_environment(args.environment);
  capture.lighting.images = args.frames;
  capture.lighting.seed = options.seed;
  capture.seed = options.seed;
  capture.response = sim::parse_response_mode(args.response);
  if (options.sensor.bit_depth) capture.bit_depth = *options.sensor.bit_depth;
  capture.check();
  const auto start = std::chrono::steady_clock::now();
  Progress progress("simulate", static_cast<std::size_t>(args.frames), "frames", mode);
  const sim::NaturalCapture natural = sim::simulate_natural(
      rig, options, capture, [&progress](std::size_t frames) { progress.advance(frames); });
  progress.finish();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  nlohmann::json simulation = sim::describe(rig, options);
  simulation["lighting"] = "natural";
  const nlohmann::json manifest = {
      {"source", "simulated"},
      {"rig", {{"name", rig.name}, {"file", rig_path.string()}}},
      {"simulation", simulation},
      {"natural_capture", natural.describe()},
  };
  io::write_stack(out, natural.stack, manifest);

  // What `solve --method shape-prior` needs besides the stack: the prior and the camera.
  const sim::Camera camera =
      sim::make_camera(rig.camera, sim::resolve_scene(options.scene).camera, options.width, options.height);
  const bool pinhole = camera.model == CameraModel::kPinhole;
  nlohmann::json solve_flags = nlohmann::json::object();
  if (pinhole) {
    // The host's pixel centres are at integer coordinates (surface/camera.hpp), the sim's at +0.5.
    std::ofstream k(out / "K.txt");
    k << fmt::format("{} 0 {}\n0 {} {}\n0 0 1\n", camera.focal_px, camera.width / 2.0 - 0.5, camera.focal_px,
                     camera.height / 2.0 - 0.5);
    if (!k) fail("{}: cannot write", (out / "K.txt").string());
    solve_flags["intrinsics"] = (out / "K.txt").string();
  } else {
    solve_flags["pixel_mm"] = camera.pixel_pitch_mm;
  }
  nlohmann::json summary = {{"stack", out.string()},
                            {"lighting", "natural"},
                            {"environment", args.environment},
                            {"response", args.response},
                            {"frames", natural.stack.frames.size()},
                            {"width", natural.stack.width()},
                            {"height", natural.stack.height()},
                            {"seconds", seconds}};
  if (args.prior_beta > 0) {
    const cv::Mat& truth = natural.stack.ground_truth->depth;
    cv::Mat prior = sim::degrade_depth(truth, natural.stack.mask,
                                       sim::PriorDegradation::beta(args.prior_beta), options.seed + 1);
    if (pinhole) {
      // The sim's depth is the height z in the dome frame; a perspective prior is the distance along the
      // axis.
      for (int r = 0; r < prior.rows; ++r)
        for (int c = 0; c < prior.cols; ++c)
          if (natural.stack.mask.at<std::uint8_t>(r, c))
            prior.at<float>(r, c) = static_cast<float>(camera.position_mm.z()) - prior.at<float>(r, c);
    }
    io::write_pfm(out / "prior.pfm", prior);
    summary["prior"] = (out / "prior.pfm").string();
    summary["prior_beta"] = args.prior_beta;
    solve_flags["prior"] = (out / "prior.pfm").string();
  }
  summary["shape_prior_flags"] = solve_flags;
  logger("host")->info("simulated {} frames of {}x{} under natural lighting in {:.2f} s into {}",
                       natural.stack.frames.size(), natural.stack.width(), natural.stack.height(), seconds,
                       out.string());
  return summary;
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
    OutputFlags output;
    SimulateArgs sim;
    NaturalArgs natural;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand(
      "simulate",
      "Render an image stack of a simulated object (--scene, --material) on the simulated dome.\n"
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
      "Output, in --out: the stack in the DiLiGenT layout (filenames.txt, 16-bit PNGs, "
      "light_directions.txt, light_intensities.txt, mask.png), ground truth (Normal_gt.png, depth_gt.pfm) "
      "and manifest.json (docs/stack-format.md). Prints one line (or --json, a summary).\n"
      "\n"
      "Examples:\n"
      "  lightstage simulate --scene bumps --material cook-torrance:roughness=0.3 --out out/bumps\n"
      "  lightstage simulate --scene bunny --lighting natural --frames 40 --width 128 --height 128 --out "
      "out/natural");
  sub->add_option("--rig", args->rig, "rig description (YAML)")->capture_default_str();
  sub->add_option("--out", args->out, "output stack folder")->required();
  add_simulate_flags(*sub, args->sim);
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
      summary = simulate_natural_to_folder(args->rig, args->sim.options, args->natural, args->out,
                                           args->output.mode());
    } else {
      const Rig rig = load_rig(args->rig);
      Progress progress("simulate", rig.leds.size(), "frames", args->output.mode());
      summary = simulate_to_folder(args->rig, args->sim.options, args->out,
                                   [&progress](std::size_t frames) { progress.advance(frames); });
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
