#include "lightstage/pipeline/simulate_folder.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/common/rig.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/output_folder.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/sim/natural_capture.hpp"
#include "lightstage/sim/scene_file.hpp"

#include <fmt/format.h>

#include <chrono>
#include <fstream>

namespace lightstage::pipeline {
namespace {

sim::NaturalLightingKind parse_environment(const std::string& text) {
  if (text == "area-lights") return sim::NaturalLightingKind::kAreaLights;
  if (text == "sh") return sim::NaturalLightingKind::kSphericalHarmonics;
  fail("--environment: '{}' is neither area-lights nor sh", text);
}

// A folder that holds something (a capture, another stack) is not written over unless asked.
void check_out(const std::filesystem::path& out, bool overwrite) {
  if (!overwrite)
    io::require_empty_folder(out, "--out", "use another --out, or --force to write the stack over it");
}

}  // namespace

nlohmann::json simulate_natural_to_folder(const std::filesystem::path& rig_path,
                                          const sim::SimulateOptions& options, const NaturalSimulation& args,
                                          const std::filesystem::path& out,
                                          const sim::FrameProgress& on_frames, bool overwrite) {
  options.check();
  check_out(out, overwrite);
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
  const sim::NaturalCapture natural = sim::simulate_natural(rig, options, capture, on_frames);
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

nlohmann::json simulate_to_folder(const std::filesystem::path& rig_path, const sim::SimulateOptions& options,
                                  const std::filesystem::path& out, const sim::FrameProgress& on_frames,
                                  bool overwrite) {
  options.check();
  check_out(out, overwrite);
  const Rig rig = load_rig(rig_path);
  const auto start = std::chrono::steady_clock::now();
  std::error_code error;
  std::filesystem::create_directories(out, error);
  if (error) fail("{}: cannot create folder: {}", out.string(), error.message());
  // A stack written over (--force) stops being one first: a simulation that fails half way must not leave
  // its index naming a mix of old and new frames.
  std::filesystem::remove(out / "filenames.txt", error);
  // Each frame goes to its file as it is rendered: the stack is never held whole.
  cv::Size size;
  const ImageStack stack = sim::simulate_stack(rig, options, on_frames, [&](std::size_t i, Frame& frame) {
    const bool is_float = frame.image.depth() == CV_32F;
    frame.filename = fmt::format("{:03}.{}", i + 1, is_float ? "pfm" : "png");
    if (is_float)
      io::write_pfm(out / frame.filename, frame.image);
    else
      io::write_png(out / frame.filename, frame.image);
    if (i == 0) size = frame.image.size();
    frame.image.release();
  });
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const nlohmann::json manifest = {
      {"source", "simulated"},
      {"rig", {{"name", rig.name}, {"file", rig_path.string()}}},
      {"simulation", sim::describe(rig, options)},
  };
  io::write_stack(out, stack, manifest, /*write_images=*/false);
  logger("host")->info("simulated {} frames of {}x{} in {:.2f} s into {}", stack.frames.size(), size.width,
                       size.height, seconds, out.string());
  return {{"stack", out.string()},
          {"frames", stack.frames.size()},
          {"width", size.width},
          {"height", size.height},
          {"seconds", seconds}};
}

}  // namespace lightstage::pipeline
