#pragma once
// The camera sensor: turns shading (linear radiance at unit light, see
// material.hpp) into 16-bit frames the way a machine-vision camera would —
// exposure, gain, noise, saturation, a response curve, black level and
// quantisation. Noise is drawn from std::mt19937_64 seeded from (seed, frame
// index) only, so images do not depend on the thread count.
//
// Signal chain, per pixel (s = shading):
//   k  = full_scale_fraction · (exposure / rig exposure) · (gain / rig gain)
//   y  = s · k                               linear, 1 = full scale
//   physical noise: e = s·fsf·(t/t_rig)·full_well + shot + read (electrons),
//                   e clipped to [.., full_well], y = e / full_well · gain / rig gain
//   signal-dependent noise (the dissertation's): y ← y + λ·y·X, X ~ N(0, 1)
//   y ← min(y, 1)  (saturation); y_r = response(y) for y >= 0, y below 0 stays linear
//   DN = round((black_level + y_r · full_code) / step) · step, clipped to [0, full_code]
// where step = 2^(16 - bits) when codes are scaled to 16 bits (default) else 1,
// and full_code = (2^bits - 1) · step = saturation_level.

#include "lightstage/common/rig.hpp"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <cstdint>
#include <optional>
#include <string>

namespace lightstage::sim {

// A camera response curve on [0, 1], monotone, with 0 → 0 and 1 → 1.
struct ResponseCurve {
  enum class Kind {
    kIdentity,
    kGamma,   // y^(1/param): "gamma:2.2" encodes like a display gamma
    kSrgb,    // the sRGB encoding curve
    kSCurve,  // y^p / (y^p + (1-y)^p), p = param > 0: contrast around 0.5
  };
  Kind kind = Kind::kIdentity;
  double param = 1.0;

  double apply(double y) const;
  std::string describe() const;
  void check() const;
  // "identity", "linear", "gamma:2.2", "srgb", "s-curve:2".
  static ResponseCurve parse(const std::string& text);
};

enum class NoiseModel {
  kNone,             // only quantisation
  kPhysical,         // photon shot noise (Gaussian, variance = electrons) + read noise
  kSignalDependent,  // the dissertation's y + λ·y·X
};

struct SensorOptions {
  std::optional<double> exposure_us;  // default: the rig camera's exposure_us
  std::optional<double> gain;         // default: the rig camera's gain
  std::optional<int> bit_depth;       // 8..16; default: the rig camera's bit_depth
  bool scale_to_16bit = true;         // store codes << (16 - bits) (true) or as they are (false)
  double black_level = 0;             // DN in stored units, added before quantisation
  double full_scale_fraction = 0.8;   // linear signal of shading 1 at the rig's exposure and gain
  NoiseModel noise = NoiseModel::kPhysical;
  double full_well_e = 20000;  // physical: electrons at full scale (shading 1/fsf at rig exposure)
  double read_noise_e = 5;     // physical: read noise standard deviation, electrons
  double lambda = 0.0;         // signal-dependent: λ
  ResponseCurve response;      // identity by default

  void check() const;
};

// SensorOptions resolved against a rig camera.
class Sensor {
 public:
  Sensor(const SensorOptions& options, const CameraDefaults& rig_camera);

  // Shading image (CV_64F or CV_32F) → frame: one channel → CV_16UC1; three
  // (BGR) → CV_16UC3, each channel through the same chain (saturation, black
  // level, response) with its own noise: channel c (0 = R, 1 = G, 2 = B) draws
  // from frame_seed(frame_seed(seed, frame_index), c + 1), a single channel
  // from frame_seed(seed, frame_index).
  cv::Mat expose(const cv::Mat& shading, std::uint64_t seed, std::uint64_t frame_index) const;

  double exposure_us() const { return exposure_us_; }
  double gain() const { return gain_; }
  int bit_depth() const { return bits_; }
  double black_level() const { return options_.black_level; }
  // Stored DN at and above which a pixel is clipped.
  double saturation_level() const { return saturation_code_; }
  // DN above black level per unit shading, under a linear response and no noise.
  double dn_per_shading() const { return k_ * full_code_; }
  nlohmann::json describe() const;

 private:
  cv::Mat expose_plane(const cv::Mat& shading, std::uint64_t rng_seed) const;  // → CV_16UC1

  SensorOptions options_;
  double exposure_us_, gain_, exposure_ratio_, gain_ratio_;
  int bits_;
  double step_, full_code_, max_code_, k_;
  double clip_y_ = 1;           // linear signal at which the well is full
  double saturation_code_ = 0;  // stored DN of a clipped pixel
};

// The generator for one frame's noise: mt19937_64 seeded from a hash of (seed, frame).
std::uint64_t frame_seed(std::uint64_t seed, std::uint64_t frame_index);

}  // namespace lightstage::sim
