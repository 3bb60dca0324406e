// `lightstage integrate`: depth and a mesh from a normal map (and optionally
// a depth prior to fuse with).
#include "commands.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/mask.hpp"
#include "lightstage/host/io/normal_map.hpp"
#include "lightstage/host/io/pfm.hpp"
#include "lightstage/host/progress.hpp"
#include "lightstage/host/surface/depth_prior.hpp"
#include "lightstage/host/surface/fusion.hpp"
#include "lightstage/host/surface/integration.hpp"
#include "lightstage/host/surface/surface_output.hpp"
#include "options.hpp"

#include <fmt/format.h>

#include <chrono>
#include <cmath>

namespace lightstage::cli {
namespace {

struct IntegrateArgs {
  std::string input, normals, mask, albedo, out, prior, intrinsics;
  std::string method = "poisson";
  std::string mesh = "ply";
  double pixel_mm = 1.0;
  double mean_depth = 1.0;
  double prior_png_scale = 1.0;
  surface::IntegrationOptions integration;
  surface::FusionOptions fusion;
  OutputFlags output;
};

// The progress line shows the share of the linear solves done (per mille).
constexpr std::size_t kProgressSteps = 1000;

cv::Mat read_albedo(const std::filesystem::path& path) {
  const cv::Mat image = io::read_image(path);
  if (image.type() == CV_32FC1) return image;
  if (image.channels() != 1) fail("{}: albedo must be a grey image", path.string());
  cv::Mat out;
  image.convertTo(out, CV_32FC1, image.depth() == CV_16U ? 1.0 / 65535 : 1.0 / 255);
  return out;
}

void run(const IntegrateArgs& a) {
  const auto start = std::chrono::steady_clock::now();
  std::filesystem::path normals_path = a.normals, albedo_path = a.albedo;
  if (!a.input.empty()) {
    // A solve result folder: normal.png, albedo.png.
    if (normals_path.empty()) normals_path = std::filesystem::path(a.input) / "normal.png";
    if (albedo_path.empty() && std::filesystem::exists(std::filesystem::path(a.input) / "albedo.png"))
      albedo_path = std::filesystem::path(a.input) / "albedo.png";
  }
  if (normals_path.empty()) fail("integrate: give --normals N.png or --input RESULT_DIR");
  const io::DecodedNormals normals = io::read_normal_map(normals_path);
  cv::Mat mask = normals.valid.clone();
  if (!a.mask.empty()) {
    const cv::Mat m = io::read_mask(a.mask);
    if (m.size() != mask.size())
      fail("{}: mask is {}x{} but the normals are {}x{}", a.mask, m.cols, m.rows, mask.cols, mask.rows);
    mask &= m;
  }
  if (cv::countNonZero(mask) == 0) fail("{}: no pixel has both a normal and the mask", normals_path.string());
  const cv::Mat albedo = albedo_path.empty() ? cv::Mat() : read_albedo(albedo_path);
  if (!albedo.empty() && albedo.size() != mask.size())
    fail("{}: albedo is {}x{} but the normals are {}x{}", albedo_path.string(), albedo.cols, albedo.rows,
         mask.cols, mask.rows);
  const surface::CameraModel camera =
      a.intrinsics.empty()
          ? surface::CameraModel::orthographic(mask.size(), a.pixel_mm)
          : surface::CameraModel::perspective(mask.size(), surface::read_intrinsics(a.intrinsics));
  surface::SurfaceResult result;
  nlohmann::json extra = {{"normals", normals_path.string()}};
  Progress progress(a.prior.empty() ? "integrate" : "fuse", kProgressSteps, "", a.output.mode());
  const surface::SurfaceProgress on_progress = [&progress](double fraction) {
    progress.advance_to(static_cast<std::size_t>(std::lround(fraction * kProgressSteps)));
  };
  if (!a.prior.empty()) {
    surface::DepthPriorOptions prior_options;
    prior_options.png_scale = a.prior_png_scale;
    const surface::DepthMap prior = surface::load_depth_prior(a.prior, camera, prior_options);
    surface::FusionOptions fusion = a.fusion;
    fusion.preserve_discontinuities = a.integration.preserve_discontinuities;
    result = surface::fuse_depth_normals(prior.depth, prior.valid, normals.normals, mask, camera, fusion,
                                         on_progress);
    extra["fusion"] = fusion.to_json();
    extra["prior"] = a.prior;
  } else {
    surface::IntegrationOptions integration = a.integration;
    integration.method = surface::parse_integration_method(a.method);
    integration.perspective_mean_depth = a.mean_depth;
    result = surface::integrate_normals(normals.normals, mask, camera, integration, on_progress);
    extra["integration"] = integration.to_json();
  }
  progress.finish();
  surface::SurfaceFiles files;
  files.ply = a.mesh == "ply" || a.mesh == "both";
  files.obj = a.mesh == "obj" || a.mesh == "both";
  const nlohmann::json summary =
      surface::write_surface_outputs(a.out, result, camera, normals.normals, albedo, files, extra);
  if (a.output.json) {
    nlohmann::json j = summary;
    j["out"] = a.out;
    j["total_seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    fmt::print("{}\n", j.dump());
  } else if (a.output.human()) {
    fmt::print("surface of {} pixels in {:.2f} s ({} solver iterations) -> {}\n", result.stats.pixels,
               result.stats.seconds, result.stats.solver_iterations, a.out);
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
      "default, up to an additive constant; perspective: distance along the axis, up to scale), depth.png, "
      "mesh.ply / mesh.obj and surface.json. Prints one line (or --json, surface.json).\n"
      "\n"
      "Example: lightstage integrate --input out/result --mask out/stack/mask.png --out out/surface --mesh "
      "both");
  sub->add_option("--input", args->input, "a solve result folder (normal.png, albedo.png)");
  sub->add_option("--normals", args->normals, "normal map (16-bit PNG, project encoding)");
  sub->add_option("--mask", args->mask, "object mask (default: where the normal map has normals)");
  sub->add_option("--albedo", args->albedo, "albedo image for the mesh colours (PNG or PFM)");
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
  add_output_flags(*sub, args->output, "surface.json plus out (the folder) and total_seconds");
  sub->callback([args, sub] {
    apply_output_flags(*sub, args->output);
    run(*args);
  });
}

}  // namespace lightstage::cli
