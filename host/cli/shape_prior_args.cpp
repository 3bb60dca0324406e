#include "shape_prior_args.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/host/surface/camera.hpp"
#include "lightstage/host/surface/depth_normals.hpp"
#include "lightstage/host/surface/depth_prior.hpp"

#include <algorithm>
#include <vector>

namespace lightstage::cli {

void add_shape_prior_flags(CLI::App& sub, ShapePriorArgs& args) {
  sub.add_option("--prior", args.prior,
                 "shape-prior: coarse depth (16-bit PNG, PFM, single-channel EXR, or a PLY mesh in the "
                 "camera frame; docs/surfaces.md)");
  sub.add_option(
      "--intrinsics", args.intrinsics,
      "shape-prior: 3x3 intrinsics (K.txt) of a perspective camera; without it the camera is orthographic");
  sub.add_option("--pixel-mm", args.pixel_mm,
                 "shape-prior: orthographic pixel size in the prior's depth unit")
      ->capture_default_str();
  sub.add_option("--sh", args.options.sh_dimension, "shape-prior: lighting dimension k, 9 or 16")
      ->check(CLI::IsMember({9, 16}))
      ->capture_default_str();
  sub.add_option("--prior-radius", args.prior_radius,
                 "shape-prior: plane-PCA radius d for the prior's normals, in its depth unit (0 = 3 pixels)")
      ->capture_default_str();
  sub.add_option("--prior-png-scale", args.png_scale, "shape-prior: depth unit per DN of a 16-bit PNG prior")
      ->capture_default_str();
  sub.add_option("--smoothing", args.options.smoothing_sigma,
                 "shape-prior: Gaussian sigma (pixels) of Eq. 4.6")
      ->capture_default_str();
  sub.add_flag("!--no-refine", args.options.refine, "shape-prior: skip the Nelder-Mead refinement (Eq. 4.7)");
}

SolveResult solve_shape_prior_method(const Observations& obs, const ShapePriorArgs& args) {
  if (args.prior.empty()) fail("--method shape-prior needs --prior DEPTH (a depth PNG, PFM, EXR or PLY)");
  const surface::CameraModel camera =
      args.intrinsics.empty()
          ? surface::CameraModel::orthographic(obs.size, args.pixel_mm)
          : surface::CameraModel::perspective(obs.size, surface::read_intrinsics(args.intrinsics));
  surface::DepthPriorOptions prior_options;
  prior_options.png_scale = args.png_scale;
  const surface::DepthMap prior = surface::load_depth_prior(args.prior, camera, prior_options);
  surface::DepthNormalsOptions normals_options;
  normals_options.radius = args.prior_radius;
  if (normals_options.radius <= 0) {
    // Three pixel footprints at the prior's median depth.
    double footprint = camera.pixel_size;
    if (camera.perspective_model()) {
      std::vector<float> depths;
      for (int r = 0; r < prior.depth.rows; ++r)
        for (int c = 0; c < prior.depth.cols; ++c)
          if (prior.valid.at<std::uint8_t>(r, c)) depths.push_back(prior.depth.at<float>(r, c));
      std::nth_element(depths.begin(), depths.begin() + static_cast<std::ptrdiff_t>(depths.size() / 2),
                       depths.end());
      footprint = depths[depths.size() / 2] / std::min(camera.K(0, 0), camera.K(1, 1));
    }
    normals_options.radius = 3 * footprint;
  }
  const surface::DepthNormals normals =
      surface::normals_from_depth(prior.depth, prior.valid, camera, normals_options);
  logger("host")->info("shape-prior: {} prior normals from {} (radius {:.3g})",
                       cv::countNonZero(normals.valid), args.prior, normals_options.radius);
  SolveResult result = solve_shape_prior(obs, normals.normals, normals.valid, args.options);
  result.parameters["prior"] = {{"file", args.prior},
                                {"camera", camera.perspective_model() ? "perspective" : "orthographic"},
                                {"intrinsics", args.intrinsics},
                                {"pixel_mm", args.pixel_mm},
                                {"radius", normals_options.radius}};
  return result;
}

}  // namespace lightstage::cli
