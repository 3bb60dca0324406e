#pragma once
// Exposure brackets merged into one linear frame (HDR). Each sample is one
// camera frame of the same still scene at its own exposure, with the dark
// frame of that exposure. Per pixel and channel:
//
//   linear_i = (raw_i − dark_i) / full_scale        linear camera
//            = response(raw_i) − dark_i             camera with an inverse response
//                                                    (the dark already linearised)
//   w_i      = hat(raw_i / sensor_full)            hat(z) = min(z, 1 − z); 0 when clipped
//   merged   = Σ w_i · linear_i / Σ w_i · t_i        (t in seconds)
//
// i.e. a weighted mean of linear_i / t_i with weights hat · t: well-exposed
// samples count most, and of two equally well exposed the longer (less noisy
// per second) more. The merged value is in units of full scale per
// exposure-second: what a one-second exposure would record, unclipped.
// full_scale is the raw type's maximum (255, 65535), as radiometry divides by.
//
// A sample is clipped when its raw value is at or above `saturation_dn`. A
// pixel with no sample but clipped ones — too dark to weigh (every raw value 0)
// — takes its longest unclipped sample. A pixel clipped at every exposure
// holds exactly `saturation_level` of the result: 1 / the shortest exposure
// in seconds (full scale at the shortest exposure, a lower bound of its
// radiance), and every other merged value stays below it, so the frame's
// saturation_level flags exactly those pixels the way a clipped code flags a
// raw frame (docs/stack-format.md).

#include "lightstage/host/capture/response_curve.hpp"

#include <opencv2/core.hpp>

#include <cstddef>
#include <vector>

namespace lightstage {

// A raw value at or above this share of the sensor's full scale counts as clipped.
inline constexpr double kClippedShare = 0.98;

struct HdrSample {
  cv::Mat image;           // raw camera frame: CV_8U or CV_16U, any channel count
  cv::Mat dark;            // this exposure's dark, same size and channels; linear domain
                           // (raw DN, or linearised values with a response); empty = 0
  double exposure_us = 0;  // > 0
};

struct HdrMergeOptions {
  double saturation_dn = 0;      // raw values at or above are clipped; 0 = kClippedShare · sensor_full_scale
  double sensor_full_scale = 0;  // the sensor's largest raw value (2^bits − 1); 0 = the type's
  const InverseResponse* response = nullptr;  // set for cameras that are not linear

  void check() const;  // throws InputError naming the field
};

struct HdrMerge {
  cv::Mat image;                     // CV_32F, the samples' channels
  double saturation_level = 0;       // the value of values clipped at every exposure
  std::size_t saturated_values = 0;  // how many (pixels × channels) are clipped at every exposure
  std::vector<std::size_t> clipped;  // per sample: values clipped in that sample
};

// Throws InputError for no samples, samples of different size or type, a dark
// that does not fit, an unsupported type or a non-positive exposure.
HdrMerge merge_hdr(const std::vector<HdrSample>& samples, const HdrMergeOptions& options = {});

}  // namespace lightstage
