#include "lightstage/pipeline/integrate_folder.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/host/io/image_io.hpp"
#include "lightstage/host/io/mask.hpp"
#include "lightstage/host/io/normal_map.hpp"
#include "lightstage/host/io/output_folder.hpp"
#include "lightstage/host/io/solve_output.hpp"
#include "lightstage/host/surface/depth_prior.hpp"
#include "lightstage/host/surface/mesh.hpp"
#include "lightstage/host/surface/surface_output.hpp"

#include <fmt/format.h>

#include <charconv>
#include <optional>

namespace lightstage::pipeline {
namespace {

// Grey or colour (BGR), as floats in [0, 1].
cv::Mat read_albedo(const std::filesystem::path& path) {
  const cv::Mat image = io::read_image(path);
  if (image.depth() == CV_32F) return image;
  cv::Mat out;
  image.convertTo(out, CV_MAKETYPE(CV_32F, image.channels()),
                  image.depth() == CV_16U ? 1.0 / 65535 : 1.0 / 255);
  return out;
}

// --mesh-step: a whole number of pixels, or nothing for "auto".
std::optional<int> parse_mesh_step(const std::string& text) {
  if (text == "auto") return std::nullopt;
  int step = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), step);
  if (error != std::errc() || end != text.data() + text.size() || step < 1)
    throw InputError(
        fmt::format("--mesh-step: '{}' is neither auto nor a whole number of pixels (1 or more)", text));
  return step;
}

}  // namespace

IntegrateReport integrate_folder(const IntegrateSettings& a, const surface::SurfaceProgress& on_progress) {
  if (a.normals.empty() && a.input.empty()) fail("integrate: give --normals N.png or --input RESULT_DIR");
  const std::optional<int> mesh_step = parse_mesh_step(a.mesh_step);
  io::require_separate_output(a.out, {a.input});
  // A solve folder gives the normals and the albedo (as albedo.png shows it) unless they are given.
  std::optional<io::SolveFolder> folder;
  if (!a.input.empty()) folder = io::read_solve_folder(a.input);
  const std::filesystem::path normals_path =
      a.normals.empty() ? std::filesystem::path(a.input) / "normal.png" : std::filesystem::path(a.normals);
  const io::DecodedNormals normals = a.normals.empty() ? io::DecodedNormals{folder->normals, folder->solved}
                                                       : io::read_normal_map(normals_path);
  cv::Mat mask = normals.valid.clone();
  if (!a.mask.empty()) {
    const cv::Mat m = io::read_mask(a.mask);
    if (m.size() != mask.size())
      fail("{}: mask is {}x{} but the normals are {}x{}", a.mask, m.cols, m.rows, mask.cols, mask.rows);
    mask &= m;
  }
  if (cv::countNonZero(mask) == 0) fail("{}: no pixel has both a normal and the mask", normals_path.string());
  const std::filesystem::path albedo_path =
      a.albedo.empty() && folder ? folder->dir / "albedo" : std::filesystem::path(a.albedo);
  const cv::Mat albedo = !a.albedo.empty() ? read_albedo(a.albedo)
                         : folder          ? folder->display_albedo()
                                           : cv::Mat();
  if (!albedo.empty() && albedo.size() != mask.size())
    fail("{}: albedo is {}x{} but the normals are {}x{}", albedo_path.string(), albedo.cols, albedo.rows,
         mask.cols, mask.rows);
  const surface::CameraModel camera =
      a.intrinsics.empty()
          ? surface::CameraModel::orthographic(mask.size(), a.pixel_mm)
          : surface::CameraModel::perspective(mask.size(), surface::read_intrinsics(a.intrinsics));
  surface::SurfaceResult result;
  nlohmann::json extra = {{"normals", normals_path.string()}};
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
  surface::SurfaceFiles files;
  files.ply = a.mesh == "ply" || a.mesh == "both";
  files.obj = a.mesh == "obj" || a.mesh == "both";
  files.mesh_step = mesh_step
                        ? *mesh_step
                        : surface::mesh_step_for(static_cast<std::size_t>(cv::countNonZero(result.valid)),
                                                 kMeshMaxVertices);
  const nlohmann::json summary =
      surface::write_surface_outputs(a.out, result, camera, normals.normals, albedo, files, extra);
  return {summary, result.stats};
}

}  // namespace lightstage::pipeline
