#pragma once
// An uncontrolled camera under natural lighting (dissertation §4.4–4.5): each
// image passes through an automatic gain and a nonlinear response — the same
// one for every image ("nonlinear-fixed", an uncalibrated camera) or a
// different random one per image ("nonlinear-random", images from
// elsewhere) — then quantisation. Plus the degraded depth priors of the
// dissertation's Fig. 4.5 (β levels: quantisation and noise).

#include "lightstage/common/image_stack.hpp"
#include "lightstage/common/rig.hpp"
#include "lightstage/sim/natural_lighting.hpp"
#include "lightstage/sim/simulate.hpp"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace lightstage::sim {

// A smooth monotone response on [0, 1] with f(0) = 0, f(1) = 1: a gamma
// encoding blended with an S-curve applied after it,
//     t = y^(1/gamma),  f = (1 − m) t + m · t^a / (t^a + (1 − t)^a).
// Measured camera curves (e.g. the DoRF database) are mostly of this kind:
// concave, sometimes with a toe and a shoulder.
struct Response {
  double gamma = 1.0;
  double s_mix = 0.0;    // m in [0, 1]
  double s_power = 1.0;  // a > 0

  double apply(double y) const;
  bool linear() const { return gamma == 1.0 && s_mix == 0.0; }
  nlohmann::json describe() const;
  // Draws gamma in [1.4, 2.8], m in [0, 0.6], a in [1, 2.5].
  static Response random(std::mt19937_64& rng);
};

enum class ResponseMode {
  kLinear,  // identity, a fixed gain
  kFixed,   // one random response for all images (and auto gain)
  kRandom,  // a random response per image (and auto gain)
};
ResponseMode parse_response_mode(const std::string& text);  // "linear" | "fixed" | "random"
const char* response_mode_name(ResponseMode mode);

struct NaturalCaptureOptions {
  NaturalLightingOptions lighting;
  ResponseMode response = ResponseMode::kRandom;
  // Auto gain: the 99th percentile of each image's shading inside the mask is
  // exposed to a random level in [min_level, max_level] of full scale.
  double min_level = 0.6, max_level = 0.95;
  int bit_depth = 16;        // quantisation of the stored 16-bit codes
  double noise_sigma = 0.0;  // additive Gaussian noise on the linear signal, fraction of full scale
  std::uint64_t seed = 1;

  void check() const;  // throws InputError naming the field
};

// What a capture produced besides its frames: the truth an evaluation needs.
struct NaturalCapture {
  ImageStack stack;  // CV_16UC1 frames (light direction unknown: +z, intensity 1), mask, ground truth
  cv::Mat albedo;    // CV_32FC1, the diffuse albedo of the scene
  std::vector<NaturalLighting> lighting;
  std::vector<Response> responses;  // per image
  std::vector<double> gains;        // per image
  // {"lighting": "natural", "per_frame": [{"lighting", "response", "gain"}, ...]}:
  // for a stack manifest's extra keys (none of them reserved there).
  nlohmann::json describe() const;
};

// Renders the scene of `simulate` (its shape, albedo and camera on `rig`)
// under natural lighting through the uncontrolled camera; `on_frames` hears
// of each image as it is done.
NaturalCapture simulate_natural(const Rig& rig, const SimulateOptions& simulate,
                                const NaturalCaptureOptions& options, const FrameProgress& on_frames = {});

// The same from ground-truth maps directly.
NaturalCapture capture_natural(const cv::Mat& normals, const cv::Mat& albedo, const cv::Mat& mask,
                               const NaturalCaptureOptions& options, int threads = 0,
                               const FrameProgress& on_frames = {});

// Depth-prior corruption of the dissertation's Fig. 4.5: depth normalised to
// [0, 1] over the mask, quantised to `bits`, Gaussian noise of `noise_sigma`
// (in the normalised unit) added, and mapped back.
struct PriorDegradation {
  int bits = 8;
  double noise_sigma = 0.0;
  // β = 1..5: (8 bits, 0.02), (6, 0.03), (5, 0.04), (4, 0.04), (3, 0.05).
  static PriorDegradation beta(int level);
  void check() const;
};

// CV_32FC1 degraded copy of `depth` (CV_32FC1) inside `mask`, 0 outside.
cv::Mat degrade_depth(const cv::Mat& depth, const cv::Mat& mask, const PriorDegradation& degradation,
                      std::uint64_t seed);

}  // namespace lightstage::sim
