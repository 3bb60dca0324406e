#pragma once
// An image stack in memory: one frame per light, with everything known about
// how each frame was taken, plus the object mask and (for simulated or
// benchmark data) the ground truth. This is the in-memory twin of a stack
// folder on disk (DiLiGenT layout + manifest, see docs/stack-format.md).

#include "lightstage/common/geometry.hpp"

#include <opencv2/core.hpp>

#include <optional>
#include <string>
#include <vector>

namespace lightstage {

struct Frame {
  std::string filename;  // relative to the stack folder, e.g. "001.png"
  // The image as captured or rendered: CV_16UC1 / CV_16UC3 (BGR) / CV_8UC1 /
  // CV_8UC3, or CV_32FC1 / CV_32FC3 for already-linear float data.
  cv::Mat image;
  Vec3 light_direction = Vec3::UnitZ();  // unit, object -> light (distant model)
  Vec3 light_intensity = Vec3::Ones();   // per channel r, g, b
  int led_id = -1;                       // -1 when not from a rig
  std::optional<Vec3> led_position_mm;   // when the light is a known near point
  double exposure_us = 0;                // 0 when unknown
  double gain = 1.0;
  double black_level = 0;  // in the image's own units (DN), subtracted by radiometry
  // The averaged dark frame taken at this frame's exposure: same size and
  // channel count as `image`, in the image's own units (any depth). When set,
  // radiometry subtracts it pixel by pixel instead of `black_level`.
  // `dark_file` names it in the stack folder (manifest key "dark"); frames
  // taken at one exposure share one dark (cv::Mat shares the pixels).
  cv::Mat dark;
  std::string dark_file;
  double saturation_level = 0;  // DN at and above which a pixel is clipped; 0 = type maximum
};

struct GroundTruth {
  cv::Mat normals;  // CV_32FC3, channels (x, y, z) in the camera frame; zero outside mask
  cv::Mat depth;    // CV_32FC1, z toward the camera (mm for rig scenes); optional
};

struct ImageStack {
  std::vector<Frame> frames;
  cv::Mat mask;  // CV_8UC1, 255 inside the object, 0 outside; empty = everywhere
  std::optional<GroundTruth> ground_truth;

  int width() const { return frames.empty() ? 0 : frames.front().image.cols; }
  int height() const { return frames.empty() ? 0 : frames.front().image.rows; }
};

}  // namespace lightstage
