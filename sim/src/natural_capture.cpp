#include "lightstage/sim/natural_capture.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/log.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace lightstage::sim {

double Response::apply(double y) const {
  const double t = std::pow(std::clamp(y, 0.0, 1.0), 1.0 / gamma);
  if (s_mix == 0) return t;
  const double a = std::pow(t, s_power), b = std::pow(1.0 - t, s_power);
  return (1.0 - s_mix) * t + s_mix * a / (a + b);
}

nlohmann::json Response::describe() const {
  return {{"gamma", gamma}, {"s_mix", s_mix}, {"s_power", s_power}};
}

Response Response::random(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Response r;
  r.gamma = 1.4 + 1.4 * u(rng);
  r.s_mix = 0.6 * u(rng);
  r.s_power = 1.0 + 1.5 * u(rng);
  return r;
}

ResponseMode parse_response_mode(const std::string& text) {
  if (text == "linear") return ResponseMode::kLinear;
  if (text == "fixed") return ResponseMode::kFixed;
  if (text == "random") return ResponseMode::kRandom;
  fail("response mode must be 'linear', 'fixed' or 'random', got '{}'", text);
}

const char* response_mode_name(ResponseMode mode) {
  switch (mode) {
    case ResponseMode::kLinear:
      return "linear";
    case ResponseMode::kFixed:
      return "fixed";
    case ResponseMode::kRandom:
      return "random";
  }
  return "?";
}

void NaturalCaptureOptions::check() const {
  lighting.check();
  if (!(min_level > 0) || max_level < min_level || max_level > 1)
    fail("natural capture: exposure levels must satisfy 0 < min <= max <= 1, got {}..{}", min_level,
         max_level);
  if (bit_depth < 8 || bit_depth > 16) fail("natural capture: bit_depth must be in 8..16, got {}", bit_depth);
  if (!(noise_sigma >= 0)) fail("natural capture: noise_sigma must be >= 0, got {}", noise_sigma);
}

nlohmann::json NaturalCapture::describe() const {
  // "per_frame", not "frames": a stack manifest reserves "frames" (one object
  // per image, docs/stack-format.md), and this object may sit at its top level.
  nlohmann::json per_frame = nlohmann::json::array();
  for (std::size_t i = 0; i < lighting.size(); ++i)
    per_frame.push_back(
        {{"lighting", lighting[i].describe()}, {"response", responses[i].describe()}, {"gain", gains[i]}});
  return {{"lighting", "natural"}, {"per_frame", per_frame}};
}

NaturalCapture capture_natural(const cv::Mat& normals, const cv::Mat& albedo, const cv::Mat& mask,
                               const NaturalCaptureOptions& options, int threads,
                               const FrameProgress& on_frames) {
  options.check();
  NaturalCapture out;
  out.lighting = random_natural_lighting(options.lighting);
  out.albedo = albedo.clone();
  std::mt19937_64 rng(options.seed ^ 0x5eedf00dULL);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const Response fixed = Response::random(rng);
  const double step = std::ldexp(1.0, 16 - options.bit_depth);
  const double full_code = (std::ldexp(1.0, options.bit_depth) - 1) * step;
  for (std::size_t i = 0; i < out.lighting.size(); ++i) {
    const cv::Mat shading = render_natural(normals, albedo, mask, out.lighting[i], threads);
    Response response;  // linear
    double gain = 0.8;
    if (options.response != ResponseMode::kLinear) {
      response = options.response == ResponseMode::kFixed ? fixed : Response::random(rng);
      std::vector<double> values;
      for (int r = 0; r < shading.rows; ++r)
        for (int c = 0; c < shading.cols; ++c)
          if (mask.at<std::uint8_t>(r, c)) values.push_back(shading.at<double>(r, c));
      double p99 = 1.0;
      if (!values.empty()) {
        auto it = values.begin() + static_cast<std::ptrdiff_t>(0.99 * static_cast<double>(values.size() - 1));
        std::nth_element(values.begin(), it, values.end());
        p99 = std::max(*it, 1e-9);
      }
      gain = (options.min_level + (options.max_level - options.min_level) * u(rng)) / p99;
    }
    Frame f;
    f.filename = fmt::format("{:03}.png", i + 1);
    f.image = cv::Mat::zeros(shading.size(), CV_16UC1);
    for (int r = 0; r < shading.rows; ++r) {
      for (int c = 0; c < shading.cols; ++c) {
        if (!mask.at<std::uint8_t>(r, c)) continue;
        double y = gain * shading.at<double>(r, c);
        if (options.noise_sigma > 0) y += options.noise_sigma * gauss(rng);
        const double code = std::round(response.apply(std::clamp(y, 0.0, 1.0)) * full_code / step) * step;
        f.image.at<std::uint16_t>(r, c) = static_cast<std::uint16_t>(std::clamp(code, 0.0, full_code));
      }
    }
    f.light_direction = Vec3::UnitZ();  // unknown: natural lighting has no single direction
    f.light_intensity = Vec3::Ones();
    f.saturation_level = full_code;
    out.stack.frames.push_back(std::move(f));
    out.responses.push_back(response);
    out.gains.push_back(gain);
    if (on_frames) on_frames(1);
  }
  out.stack.mask = mask.clone();
  out.stack.ground_truth = GroundTruth{normals.clone(), {}};
  return out;
}

NaturalCapture simulate_natural(const Rig& rig, const SimulateOptions& simulate,
                                const NaturalCaptureOptions& options, const FrameProgress& on_frames) {
  const World world(rig, simulate);
  if (world.has_colour()) {
    logger("sim")->warn(
        "natural lighting renders grey: scene '{}' has a colour, left out (the frames are its "
        "BT.601 grey)",
        world.scene().name);
  }
  const Renderer& renderer = world.renderer();
  NaturalCapture out = capture_natural(renderer.ground_truth().normals, renderer.albedo_map(),
                                       renderer.mask(), options, simulate.threads, on_frames);
  out.stack.ground_truth->depth = renderer.ground_truth().depth.clone();
  return out;
}

PriorDegradation PriorDegradation::beta(int level) {
  switch (level) {
    case 1:
      return {8, 0.02};
    case 2:
      return {6, 0.03};
    case 3:
      return {5, 0.04};
    case 4:
      return {4, 0.04};
    case 5:
      return {3, 0.05};
    default:
      fail("prior degradation: beta level must be 1..5, got {}", level);
  }
}

void PriorDegradation::check() const {
  if (bits < 1 || bits > 24) fail("prior degradation: bits must be in 1..24, got {}", bits);
  if (!(noise_sigma >= 0)) fail("prior degradation: noise_sigma must be >= 0, got {}", noise_sigma);
}

cv::Mat degrade_depth(const cv::Mat& depth, const cv::Mat& mask, const PriorDegradation& degradation,
                      std::uint64_t seed) {
  degradation.check();
  if (depth.type() != CV_32FC1 || mask.type() != CV_8UC1 || depth.size() != mask.size())
    fail("degrade_depth: depth CV_32FC1 and mask CV_8UC1 of one size are needed");
  double lo = 0, hi = 0;
  cv::minMaxLoc(depth, &lo, &hi, nullptr, nullptr, mask);
  const double range = std::max(hi - lo, 1e-12);
  const double levels = std::ldexp(1.0, degradation.bits) - 1;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0.0, degradation.noise_sigma > 0 ? degradation.noise_sigma : 1.0);
  cv::Mat out = cv::Mat::zeros(depth.size(), CV_32FC1);
  for (int r = 0; r < depth.rows; ++r) {
    for (int c = 0; c < depth.cols; ++c) {
      if (!mask.at<std::uint8_t>(r, c)) continue;
      double t = std::round((depth.at<float>(r, c) - lo) / range * levels) / levels;
      if (degradation.noise_sigma > 0) t += gauss(rng);
      out.at<float>(r, c) = static_cast<float>(lo + t * range);
    }
  }
  return out;
}

}  // namespace lightstage::sim
