#include "lightstage/pipeline/shape_prior_method.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/host/surface/camera.hpp"
#include "lightstage/host/surface/depth_normals.hpp"
#include "lightstage/host/surface/depth_prior.hpp"

#include <algorithm>
#include <vector>

namespace lightstage::pipeline {

SolveResult solve_with_shape_prior(const Observations& obs, const ShapePriorSettings& args) {
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

}  // namespace lightstage::pipeline
