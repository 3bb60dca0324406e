#pragma once
// Depth priors from outside (a depth sensor, multi-view stereo, a known
// shape): a 16-bit depth PNG, a float PFM or EXR, or a PLY mesh rendered into
// the camera. Depth values follow camera.hpp (orthographic: height toward the
// camera; perspective: distance along the optical axis).

#include "lightstage/host/surface/camera.hpp"
#include "lightstage/host/surface/mesh.hpp"

#include <opencv2/core.hpp>

#include <filesystem>

namespace lightstage::surface {

struct DepthPriorOptions {
  // 16-bit PNG: depth = DN · png_scale + png_offset (Kinect-style files store millimetres: scale 1).
  double png_scale = 1.0;
  double png_offset = 0.0;

  void check() const;  // throws InputError naming the field
};

struct DepthMap {
  cv::Mat depth;  // CV_32FC1, 0 where invalid
  cv::Mat valid;  // CV_8UC1, 255 where the prior has a depth
};

// By extension: .png (16-bit grey; 0 = no depth), .pfm (one channel; 0 or not
// finite = no depth), .exr (one HALF or FLOAT channel named Y, Z or R, read
// through io/exr.hpp; 0 or not finite = no depth), .ply (a mesh in the camera
// frame, rendered with a z-buffer). The result has the camera's size; throws InputError naming the
// file when it is unreadable, of another size, or holds no depth at all.
DepthMap load_depth_prior(const std::filesystem::path& path, const CameraModel& camera,
                          const DepthPriorOptions& options = {});

// Renders a mesh's depth into the camera (nearest surface wins; depth is
// interpolated perspective-correctly). Pixels no triangle covers are invalid.
DepthMap render_depth(const Mesh& mesh, const CameraModel& camera);

}  // namespace lightstage::surface
