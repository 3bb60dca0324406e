#include "lightstage/host/shadow_threshold.hpp"

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

// Each sampled mask pixel's darkest observation.
std::vector<float> darkest_observations(const Observations& observations) {
  std::vector<float> darkest;
  const auto rows = static_cast<std::size_t>(observations.intensities.rows());
  if (observations.intensities.cols() == 0) return darkest;
  const std::size_t stride = std::max<std::size_t>(1, rows / kMaxObjectPixels);
  for (std::size_t p = 0; p < rows; p += stride)
    darkest.push_back(observations.intensities.row(static_cast<Eigen::Index>(p)).minCoeff());
  return darkest;
}

// A camera without a black level clips the negative half of the noise in its
// shadows to exact zeros: a shadowed pixel then has zeros and about as many
// small positive values, the noise's other half (a half-normal whose 1 σ
// quantile is σ). Noise-free data has zeros too, but the values next to them
// are the dimmest shading, a sizeable part of the pixel's lit values; so the
// partners count as noise only when they sit far below those. 0 = not found.
double clipped_noise_sigma(const Observations& observations) {
  const auto rows = static_cast<std::size_t>(observations.intensities.rows());
  const auto images = static_cast<std::size_t>(observations.intensities.cols());
  if (images == 0) return 0;
  const std::size_t stride = std::max<std::size_t>(1, rows / kMaxObjectPixels);
  std::vector<float> partners, lit_medians, positive;
  for (std::size_t p = 0; p < rows; p += stride) {
    const auto row = observations.intensities.row(static_cast<Eigen::Index>(p));
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
    partners.insert(partners.end(), positive.begin(), positive.begin() + static_cast<std::ptrdiff_t>(zeros));
    lit_medians.push_back(positive[positive.size() / 2]);
  }
  if (partners.size() < kMinClippedSamples) return 0;
  const double sigma = quantile(partners, kHalfNormalSigmaQuantile);
  return sigma < kMaxClippedNoiseRatio * quantile(lit_medians, 0.5) ? sigma : 0;
}

// Every frame's values at a sample of the pixels outside the (dilated) mask.
std::vector<float> background_values(const ImageStack& stack) {
  std::vector<float> values;
  if (stack.mask.empty() || stack.frames.empty()) return values;
  cv::Mat near_object;
  cv::dilate(stack.mask, near_object, cv::Mat(), cv::Point(-1, -1), kBackgroundMarginPx);
  const int outside = static_cast<int>(near_object.total()) - cv::countNonZero(near_object);
  if (outside <= 0) return values;
  const int stride = std::max(1, outside / static_cast<int>(kMaxBackgroundPixels));
  ImageStack background = stack;  // frames share their images
  background.mask = cv::Mat(stack.mask.size(), CV_8UC1, cv::Scalar::all(0));
  int seen = 0;
  for (int y = 0; y < near_object.rows; ++y) {
    const auto* in = near_object.ptr<std::uint8_t>(y);
    auto* out = background.mask.ptr<std::uint8_t>(y);
    for (int x = 0; x < near_object.cols; ++x) {
      if (in[x] == 0 && seen++ % stride == 0) out[x] = 255;
    }
  }
  const Observations observations = make_observations(background);
  values.assign(observations.intensities.data(),
                observations.intensities.data() + observations.intensities.size());
  return values;
}

ShadowThreshold estimate(const std::vector<float>& darkest, const std::vector<float>& background,
                         double clipped_sigma, std::string source) {
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

std::string source_of(const ImageStack& stack) {
  const bool darks =
      std::any_of(stack.frames.begin(), stack.frames.end(), [](const Frame& f) { return !f.dark.empty(); });
  if (darks) return "dark frames";
  const bool black =
      std::any_of(stack.frames.begin(), stack.frames.end(), [](const Frame& f) { return f.black_level > 0; });
  return black ? "black level" : "noise floor";
}

}  // namespace

nlohmann::json ShadowThreshold::to_json() const {
  return {{"value", value},
          {"source", source},
          {"level", level},
          {"noise", noise},
          {"object_samples", object_samples},
          {"background_samples", background_samples}};
}

std::string ShadowThreshold::describe() const {
  if (source == "flag") return fmt::format("shadow threshold {:.4g} (--shadow-threshold)", value);
  return fmt::format("shadow threshold {:.4g} ({}: level {:.4g}, noise {:.4g})", value, source, level, noise);
}

ShadowThreshold estimate_shadow_threshold(const ImageStack& stack, const Observations& observations) {
  return estimate(darkest_observations(observations), background_values(stack),
                  clipped_noise_sigma(observations), source_of(stack));
}

ShadowThreshold estimate_shadow_threshold(const Observations& observations) {
  return estimate(darkest_observations(observations), {}, clipped_noise_sigma(observations), "noise floor");
}

}  // namespace lightstage
