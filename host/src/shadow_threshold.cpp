#include "lightstage/host/shadow_threshold.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/image_stack.hpp"
#include "lightstage/host/radiometry.hpp"

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

namespace lightstage {
namespace {

// Enough samples for stable quantiles, few enough to cost nothing beside the solve.
constexpr std::size_t kMaxObjectPixels = 20000;
constexpr std::size_t kMaxBackgroundPixels = 2000;
// Background pixels this close to the mask may still see the object (blur, a loose mask).
constexpr int kBackgroundMarginPx = 5;
constexpr std::size_t kMinBackgroundValues = 1000;
constexpr double kOneSigmaQuantile = 0.8413;  // median + 1 σ of a normal distribution
constexpr double kDarkestLevelQuantile = 0.1, kDarkestNoiseQuantile = 0.25;
constexpr double kNoiseSigmas = 3;
constexpr double kMaxLevelBias = 0.1;
// Clipped noise (below): the half-normal's 1 σ quantile, the fewest partner
// values worth a quantile, and how far under the lit values noise must sit
// to be told from the dimmest shading of noise-free data.
constexpr double kHalfNormalSigmaQuantile = 0.6827;
constexpr std::size_t kMinClippedSamples = 200;
constexpr double kMaxClippedNoiseRatio = 0.05;

double quantile(std::vector<float> values, double q) {
  if (values.empty()) return 0;
  const auto k = static_cast<std::size_t>(std::lround(q * static_cast<double>(values.size() - 1)));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

// One in every `stride` of the whole image's mask pixels (in scan order) is sampled.
std::size_t object_stride(std::size_t total_pixels) {
  return std::max<std::size_t>(1, total_pixels / kMaxObjectPixels);
}

}  // namespace

ShadowSamples::ShadowSamples(std::size_t total_pixels) : stride_(object_stride(total_pixels)) {}

void ShadowSamples::add_object(const Observations& observations) {
  const auto rows = static_cast<std::size_t>(observations.intensities.rows());
  if (observations.intensities.cols() == 0) return;
  std::vector<float> positive;
  // The first pixel of these observations that falls on the whole image's stride.
  const std::size_t first = observations.first_pixel;
  for (std::size_t p = (stride_ - first % stride_) % stride_; p < rows; p += stride_) {
    const auto row = observations.intensities.row(static_cast<Eigen::Index>(p));
    // Each sampled mask pixel's darkest observation.
    darkest_.push_back(row.minCoeff());
    // A camera without a black level clips the negative half of the noise in
    // its shadows to exact zeros: a shadowed pixel then has zeros and about as
    // many small positive values, the noise's other half (a half-normal whose
    // 1 σ quantile is σ). Noise-free data has zeros too, but the values next
    // to them are the dimmest shading, a sizeable part of the pixel's lit
    // values; so the partners count as noise only when they sit far below those.
    positive.clear();
    std::size_t zeros = 0;
    for (Eigen::Index j = 0; j < row.size(); ++j) {
      if (!std::isfinite(row(j))) continue;
      if (row(j) <= 0) {
        ++zeros;
      } else {
        positive.push_back(row(j));
      }
    }
    if (zeros == 0 || positive.size() < 2 * zeros) continue;
    std::sort(positive.begin(), positive.end());
    partners_.insert(partners_.end(), positive.begin(),
                     positive.begin() + static_cast<std::ptrdiff_t>(zeros));
    lit_medians_.push_back(positive[positive.size() / 2]);
  }
}

void ShadowSamples::add_background(const Observations& background) {
  background_.insert(background_.end(), background.intensities.data(),
                     background.intensities.data() + background.intensities.size());
}

ShadowThreshold ShadowSamples::estimate(std::string source) const {
  const std::vector<float>& darkest = darkest_;
  const std::vector<float>& background = background_;
  // The clipped noise's σ; 0 = not found.
  double clipped_sigma = 0;
  if (partners_.size() >= kMinClippedSamples) {
    const double sigma = quantile(partners_, kHalfNormalSigmaQuantile);
    if (sigma < kMaxClippedNoiseRatio * quantile(lit_medians_, 0.5)) clipped_sigma = sigma;
  }
  ShadowThreshold t;
  t.source = std::move(source);
  t.object_samples = darkest.size();
  t.background_samples = background.size();
  if (background.size() >= kMinBackgroundValues) {
    // The background is what the camera reads where no light is shaded into
    // the object: its median is the level; the spread above the median (a
    // level at a clipped zero has no spread below it) is the noise.
    t.level = quantile(background, 0.5);
    t.noise = quantile(background, kOneSigmaQuantile) - t.level;
  } else if (clipped_sigma > 0) {
    // No background, shadows clipped at zero: the level is zero, the partners give σ.
    t.level = 0;
    t.noise = clipped_sigma;
  } else if (!darkest.empty()) {
    // No background: the darkest observations of the pixels that have
    // shadows (a low quantile: many pixels may have none).
    t.level = quantile(darkest, kDarkestLevelQuantile);
    t.noise = quantile(darkest, kDarkestNoiseQuantile) - t.level;
  }
  t.level = std::max(t.level, 0.0);
  t.noise = std::max(t.noise, 0.0);
  // Above the noise, and far enough above the level that it biases a kept
  // value by at most kMaxLevelBias (the level is stray light or an offset,
  // added to every observation: near the terminator it is most of the value).
  t.value = std::max({kMinShadowThreshold, t.level + kNoiseSigmas * t.noise, t.level / kMaxLevelBias});
  return t;
}

cv::Mat background_sample_mask(const cv::Mat& mask) {
  if (mask.empty()) return {};
  cv::Mat near_object;
  cv::dilate(mask, near_object, cv::Mat(), cv::Point(-1, -1), kBackgroundMarginPx);
  const int outside = static_cast<int>(near_object.total()) - cv::countNonZero(near_object);
  if (outside <= 0) return {};
  const int stride = std::max(1, outside / static_cast<int>(kMaxBackgroundPixels));
  cv::Mat sample(mask.size(), CV_8UC1, cv::Scalar::all(0));
  int seen = 0;
  for (int y = 0; y < near_object.rows; ++y) {
    const auto* in = near_object.ptr<std::uint8_t>(y);
    auto* out = sample.ptr<std::uint8_t>(y);
    for (int x = 0; x < near_object.cols; ++x) {
      if (in[x] == 0 && seen++ % stride == 0) out[x] = 255;
    }
  }
  return sample;
}

std::string shadow_threshold_source(const ImageStack& stack) {
  const bool darks = std::any_of(stack.frames.begin(), stack.frames.end(),
                                 [](const Frame& f) { return !f.dark.empty() || !f.dark_file.empty(); });
  if (darks) return "dark frames";
  const bool black =
      std::any_of(stack.frames.begin(), stack.frames.end(), [](const Frame& f) { return f.black_level > 0; });
  return black ? "black level" : "noise floor";
}

nlohmann::json ShadowThreshold::to_json() const {
  return {{"value", value},
          {"source", source},
          {"level", level},
          {"noise", noise},
          {"object_samples", object_samples},
          {"background_samples", background_samples}};
}

ShadowThreshold ShadowThreshold::from_json(const nlohmann::json& json) {
  ShadowThreshold threshold;
  try {
    threshold.value = json.at("value").get<double>();
    threshold.source = json.at("source").get<std::string>();
    threshold.level = json.value("level", 0.0);
    threshold.noise = json.value("noise", 0.0);
    threshold.object_samples = json.value("object_samples", std::size_t{0});
    threshold.background_samples = json.value("background_samples", std::size_t{0});
  } catch (const nlohmann::json::exception& e) {
    fail("shadow threshold: {}", e.what());
  }
  return threshold;
}

std::string ShadowThreshold::describe() const {
  if (source == "flag") return fmt::format("shadow threshold {:.4g} (--shadow-threshold)", value);
  return fmt::format("shadow threshold {:.4g} ({}: level {:.4g}, noise {:.4g})", value, source, level, noise);
}

ShadowThreshold estimate_shadow_threshold(const ImageStack& stack, const Observations& observations) {
  ShadowSamples samples(observations.pixel_count());
  samples.add_object(observations);
  const cv::Mat background = background_sample_mask(stack.mask);
  if (!background.empty()) {
    ImageStack sampled = stack;  // frames share their images
    sampled.mask = background;
    samples.add_background(make_observations(sampled));
  }
  return samples.estimate(shadow_threshold_source(stack));
}

ShadowThreshold estimate_shadow_threshold(const Observations& observations) {
  ShadowSamples samples(observations.pixel_count());
  samples.add_object(observations);
  return samples.estimate("noise floor");
}

}  // namespace lightstage
