#pragma once
// Radiometry: from an ImageStack to what the solvers consume. For each frame
// and each pixel inside the mask:
//   value = (raw − black_level) / full_scale / light_intensity   (per channel)
// with full_scale = 65535 for 16-bit, 255 for 8-bit and 1 for float images;
// colour images are then made grey with BT.601 weights (0.2989 R + 0.5870 G +
// 0.1140 B; OpenCV's BGR order is handled here); grey images are divided by
// the BT.601 grey of the light intensity instead. Finally values are clamped
// to ≤ 1 (optional, on by default: the DiLiGenT baseline is computed so).
// Values below 0 (black level above the raw value) are kept as they are.
//
// Dark subtraction: a frame with a dark frame (Frame::dark, the averaged
// dark of its exposure) has it subtracted pixel by pixel, channel by channel,
// in place of black_level; a frame without one (DiLiGenT, simulated stacks,
// captures without darks) falls back to the scalar black_level. The pixel
// pattern of a dark (hot pixels, amplifier glow, column offsets) is so
// removed where a scalar level would leave it in the signal.
//
// Colour: a colour stack also gives each pixel its chromaticity, the share of
// each linear channel in the grey (chroma_c = value_c / grey, so that the
// BT.601 grey of the chroma is 1): the per-channel median over the pixel's lit,
// unsaturated observations (grey at least kChromaMinShare of its brightest).
// The median follows the diffuse colour and not a white highlight that lights
// a minority of the frames (the dichromatic rule of dielectrics). Relighting
// multiplies its grey by it (reflectance/relight.hpp).
//
// Saturation is reported beside the values, not folded into them: an
// observation is saturated when any raw channel is ≥ the frame's saturation
// level (Frame::saturation_level, or the type maximum when that is 0; float
// images are never saturated unless a level is given). Solvers that care drop
// those observations; the Lambertian baseline ignores the flags.

#include "lightstage/common/image_stack.hpp"
#include "lightstage/host/near_lights.hpp"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <cstddef>
#include <optional>
#include <vector>

namespace lightstage {

// Observations darker than this share of a pixel's brightest are left out of
// its chroma (their ratios are mostly noise).
inline constexpr double kChromaMinShare = 0.05;

struct RadiometryOptions {
  // Clamp normalised grey values to ≤ 1 (DiLiGenT's ball: 4.10° mean error with, 4.17° without).
  bool clamp_to_one = true;
  // Threads converting frames; 0 = hardware concurrency.
  int threads = 0;

  // Throws InputError naming the broken field and value.
  void check() const;
};

using ObservationMatrix = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using FlagMatrix = Eigen::Matrix<bool, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Solver input: one row per pixel inside the mask, one column per image.
struct Observations {
  cv::Size size;                  // image size
  cv::Mat mask;                   // CV_8UC1, 255 exactly at `pixels`
  std::vector<cv::Point> pixels;  // (x = column, y = row) inside the mask, row-major scan order
  ObservationMatrix intensities;  // pixels × images, linear grey values as above
  FlagMatrix saturated;           // pixels × images, true = raw value at or above saturation
  // Colour stacks: pixels × 3 (r, g, b) chroma as above; empty for grey stacks.
  Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor> chroma;
  Eigen::MatrixX3d lights;  // images × 3, unit light directions (object -> light)
  // Set when LED positions are known: per-pixel directions and falloff
  // (near_light_directions) replace `lights`, which stays the distant approximation.
  std::optional<NearLights> near;
  // A band of a larger image (io/stack_bands.hpp): where the band's (0, 0)
  // lies in the whole image, the whole image's size, and the index of
  // pixels[0] among the whole image's pixels. `size`, `mask` and `pixels`
  // are the band's own; what depends on a pixel's place in the image (near
  // lights, a pixel's random seed) uses these.
  cv::Point origin;
  cv::Size whole_size;  // empty: `size`
  std::size_t first_pixel = 0;

  std::size_t pixel_count() const { return pixels.size(); }
  std::size_t image_count() const { return static_cast<std::size_t>(lights.rows()); }
  cv::Size image_size() const { return whole_size.empty() ? size : whole_size; }
};

// Converts `stack` as described above. An empty stack mask means every pixel.
// Throws InputError when the stack has no frames, frames of different size or
// type, an unsupported pixel type, a dark frame that does not fit its frame,
// or a mask of the wrong size or type.
Observations make_observations(const ImageStack& stack, const RadiometryOptions& options = {});

// The chroma of `obs` as an image: CV_32FC3 in OpenCV's (b, g, r) order, 0
// where `solved` (CV_8UC1, or empty = every observed pixel) is 0 and off the
// observed pixels. Empty when the observations have no chroma (grey stacks).
cv::Mat chroma_image(const Observations& obs, const cv::Mat& solved = {});

}  // namespace lightstage
