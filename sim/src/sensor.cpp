#include "lightstage/sim/sensor.hpp"

#include "lightstage/common/error.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <random>
#include <vector>

namespace lightstage::sim {
namespace {

std::uint64_t mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

double srgb_encode(double y) { return y <= 0.0031308 ? 12.92 * y : 1.055 * std::pow(y, 1.0 / 2.4) - 0.055; }

}  // namespace

std::uint64_t frame_seed(std::uint64_t seed, std::uint64_t frame_index) {
  return mix(mix(seed) ^ frame_index);
}

double ResponseCurve::apply(double y) const {
  y = std::clamp(y, 0.0, 1.0);
  switch (kind) {
    case Kind::kIdentity:
      return y;
    case Kind::kGamma:
      return std::pow(y, 1.0 / param);
    case Kind::kSrgb:
      return std::min(1.0, srgb_encode(y));  // 1.055 - 0.055 is 1 up to rounding
    case Kind::kSCurve: {
      const double a = std::pow(y, param);
      const double b = std::pow(1.0 - y, param);
      return a / (a + b);
    }
  }
  return y;
}

std::string ResponseCurve::describe() const {
  switch (kind) {
    case Kind::kIdentity:
      return "identity";
    case Kind::kGamma:
      return fmt::format("gamma:{}", param);
    case Kind::kSrgb:
      return "srgb";
    case Kind::kSCurve:
      return fmt::format("s-curve:{}", param);
  }
  return "?";
}

void ResponseCurve::check() const {
  if ((kind == Kind::kGamma || kind == Kind::kSCurve) && !(param > 0 && std::isfinite(param))) {
    fail("sensor response: parameter of '{}' must be positive, got {}", describe(), param);
  }
}

ResponseCurve ResponseCurve::parse(const std::string& text) {
  ResponseCurve r;
  const auto colon = text.find(':');
  const std::string name = text.substr(0, colon);
  const std::string arg = colon == std::string::npos ? "" : text.substr(colon + 1);
  auto number = [&](double fallback) {
    if (arg.empty()) return fallback;
    char* end = nullptr;
    const double v = std::strtod(arg.c_str(), &end);
    if (!end || *end != '\0') fail("sensor response '{}': '{}' is not a number", text, arg);
    return v;
  };
  if (name == "identity" || name == "linear") {
    r.kind = Kind::kIdentity;
  } else if (name == "gamma") {
    r.kind = Kind::kGamma;
    r.param = number(2.2);
  } else if (name == "srgb") {
    r.kind = Kind::kSrgb;
  } else if (name == "s-curve") {
    r.kind = Kind::kSCurve;
    r.param = number(2.0);
  } else {
    fail("sensor response '{}': unknown curve (known: identity, gamma:<g>, srgb, s-curve:<p>)", text);
  }
  if ((r.kind == Kind::kIdentity || r.kind == Kind::kSrgb) && !arg.empty()) {
    fail("sensor response '{}': '{}' takes no parameter", text, name);
  }
  r.check();
  return r;
}

void SensorOptions::check() const {
  if (exposure_us && !(*exposure_us > 0 && std::isfinite(*exposure_us))) {
    fail("sensor: exposure_us must be positive, got {}", *exposure_us);
  }
  if (gain && !(*gain > 0 && std::isfinite(*gain))) fail("sensor: gain must be positive, got {}", *gain);
  if (bit_depth && (*bit_depth < 8 || *bit_depth > 16))
    fail("sensor: bit_depth must be in 8..16, got {}", *bit_depth);
  if (!(black_level >= 0 && black_level < 65535))
    fail("sensor: black_level must be in [0, 65535), got {}", black_level);
  if (!(full_scale_fraction > 0 && std::isfinite(full_scale_fraction))) {
    fail("sensor: full_scale_fraction must be positive, got {}", full_scale_fraction);
  }
  if (!(full_well_e > 0 && std::isfinite(full_well_e)))
    fail("sensor: full_well_e must be positive, got {}", full_well_e);
  if (!(read_noise_e >= 0 && std::isfinite(read_noise_e))) {
    fail("sensor: read_noise_e must not be negative, got {}", read_noise_e);
  }
  if (!(lambda >= 0 && std::isfinite(lambda))) fail("sensor: lambda must not be negative, got {}", lambda);
  response.check();
}

Sensor::Sensor(const SensorOptions& options, const CameraDefaults& rig_camera) : options_(options) {
  options_.check();
  exposure_us_ = options.exposure_us.value_or(rig_camera.exposure_us);
  gain_ = options.gain.value_or(rig_camera.gain);
  bits_ = options.bit_depth.value_or(rig_camera.bit_depth);
  if (bits_ < 8 || bits_ > 16) fail("sensor: bit_depth must be in 8..16, got {}", bits_);
  exposure_ratio_ = rig_camera.exposure_us > 0 ? exposure_us_ / rig_camera.exposure_us : 1.0;
  gain_ratio_ = rig_camera.gain > 0 ? gain_ / rig_camera.gain : 1.0;
  step_ = options.scale_to_16bit ? std::ldexp(1.0, 16 - bits_) : 1.0;
  max_code_ = std::ldexp(1.0, bits_) - 1;
  full_code_ = max_code_ * step_;
  if (options.black_level >= full_code_) {
    fail("sensor: black_level {} must be below the full-scale code {}", options.black_level, full_code_);
  }
  k_ = options.full_scale_fraction * exposure_ratio_ * gain_ratio_;
  // The pixel well fills at the rig gain's full scale: below that gain the
  // brightest code is under full scale, and that code is where clipping starts.
  clip_y_ = std::min(1.0, gain_ratio_);
  saturation_code_ =
      std::min(max_code_,
               std::nearbyint((options.black_level + options.response.apply(clip_y_) * full_code_) / step_)) *
      step_;
}

cv::Mat Sensor::expose(const cv::Mat& shading, std::uint64_t seed, std::uint64_t frame_index) const {
  CV_Assert((shading.channels() == 1 || shading.channels() == 3) &&
            (shading.depth() == CV_64F || shading.depth() == CV_32F));
  if (shading.channels() == 1) return expose_plane(shading, frame_seed(seed, frame_index));
  std::vector<cv::Mat> planes;
  cv::split(shading, planes);  // B, G, R
  const std::uint64_t frame = frame_seed(seed, frame_index);
  std::vector<cv::Mat> frames(3);
  for (int rgb = 0; rgb < 3; ++rgb) {
    const auto plane = static_cast<std::size_t>(2 - rgb);
    frames[plane] = expose_plane(planes[plane], frame_seed(frame, static_cast<std::uint64_t>(rgb) + 1));
  }
  cv::Mat out;
  cv::merge(frames, out);
  return out;
}

cv::Mat Sensor::expose_plane(const cv::Mat& shading, std::uint64_t rng_seed) const {
  cv::Mat s;
  shading.convertTo(s, CV_64F);
  cv::Mat out(s.size(), CV_16UC1);
  std::mt19937_64 rng(rng_seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const double fw = options_.full_well_e;
  const double electrons_per_shading = options_.full_scale_fraction * exposure_ratio_ * fw;
  for (int r = 0; r < s.rows; ++r) {
    const double* in = s.ptr<double>(r);
    auto* o = out.ptr<std::uint16_t>(r);
    for (int c = 0; c < s.cols; ++c) {
      const double value = std::isfinite(in[c]) ? std::max(in[c], 0.0) : 0.0;
      double y = value * k_;
      switch (options_.noise) {
        case NoiseModel::kNone:
          break;
        case NoiseModel::kPhysical: {
          const double mean = value * electrons_per_shading;
          double e = mean + std::sqrt(mean) * normal(rng) + options_.read_noise_e * normal(rng);
          e = std::min(e, fw);
          y = e / fw * gain_ratio_;
          break;
        }
        case NoiseModel::kSignalDependent:
          y += options_.lambda * y * normal(rng);
          break;
      }
      y = std::min(y, clip_y_);
      const double yr = y >= 0 ? options_.response.apply(y) : y;
      double code = std::nearbyint((options_.black_level + yr * full_code_) / step_);
      code = std::isfinite(code) ? std::clamp(code, 0.0, max_code_) : 0.0;
      o[c] = static_cast<std::uint16_t>(code * step_);
    }
  }
  return out;
}

nlohmann::json Sensor::describe() const {
  const char* noise = options_.noise == NoiseModel::kNone       ? "none"
                      : options_.noise == NoiseModel::kPhysical ? "physical"
                                                                : "signal-dependent";
  nlohmann::json j{{"exposure_us", exposure_us_},
                   {"gain", gain_},
                   {"bit_depth", bits_},
                   {"scale_to_16bit", options_.scale_to_16bit},
                   {"black_level", options_.black_level},
                   {"saturation_level", saturation_code_},
                   {"full_scale_fraction", options_.full_scale_fraction},
                   {"noise", noise},
                   {"response", options_.response.describe()}};
  if (options_.noise == NoiseModel::kPhysical) {
    j["full_well_e"] = options_.full_well_e;
    j["read_noise_e"] = options_.read_noise_e;
  }
  if (options_.noise == NoiseModel::kSignalDependent) j["lambda"] = options_.lambda;
  return j;
}

}  // namespace lightstage::sim
