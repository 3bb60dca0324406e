#pragma once
// The shadow threshold from the data itself: the level at or below which an
// observation (a value at unit light, radiometry.hpp) is a shadow, not a lit
// value. A fixed threshold cannot be right everywhere: noise-free synthetic
// data has exact zeros in shadow, while a real camera reads its dark noise,
// stray light and interreflections there (DiLiGenT's ball: a few thousandths,
// which a threshold of 1e-6 reads as lit and which then rank as the darkest
// lit observations, those T_low keeps).
//
// The shadows are modelled as a level b (what is left after the black level
// or dark frame: stray light, bias) plus noise of spread σ; the threshold is
// b + kSigmas·σ, at least kMinShadowThreshold. b and σ come from the dark
// population: each mask pixel's darkest observations and, when the stack has
// a mask, the background pixels outside it in every frame (a surface that is
// not the object reads what the camera reads without the object's shading).
// Without a background, shadows clipped at zero (no black level) give the
// noise through the small values that pair with their exact zeros.
// Where the stack subtracted dark frames or a black level the source says so:
// the level then starts from zero by construction and the spread is what is
// left to estimate.

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <cstddef>
#include <string>
#include <vector>

namespace lightstage {

struct ImageStack;
struct Observations;

// Noise-free data (exact zeros in shadow) keeps the synthetic default.
inline constexpr double kMinShadowThreshold = 1e-6;

struct ShadowThreshold {
  double value = kMinShadowThreshold;
  // How the value was chosen: "flag" (--shadow-threshold), "dark frames",
  // "black level" or "noise floor" (neither: from the data alone).
  std::string source = "noise floor";
  double level = 0;                    // b, the shadows' level
  double noise = 0;                    // σ, their spread
  std::size_t object_samples = 0;      // darkest observations of mask pixels used
  std::size_t background_samples = 0;  // background values used

  nlohmann::json to_json() const;
  // Reads to_json()'s output back; throws InputError naming the missing or malformed field.
  static ShadowThreshold from_json(const nlohmann::json& json);
  // "shadow threshold 0.0123 (noise floor: level 0.0041, noise 0.0027)".
  std::string describe() const;
};

// What the threshold is estimated from, gathered from the whole image at once
// or band by band (a stack read in bands, io/stack_bands.hpp) with the same
// result: one in every so many of the whole image's mask pixels, by their
// place in scan order (Observations::first_pixel), and the background pixels
// background_sample_mask picks.
class ShadowSamples {
 public:
  // `total_pixels`: the mask pixels of the whole image.
  explicit ShadowSamples(std::size_t total_pixels);
  // The object's observations: the whole image's, or one band's after another.
  void add_object(const Observations& observations);
  // Observations of the background_sample_mask pixels (of the whole image or a band).
  void add_background(const Observations& background);
  // `source`: shadow_threshold_source of the stack, or "noise floor".
  ShadowThreshold estimate(std::string source) const;

 private:
  std::size_t stride_ = 1;
  std::vector<float> darkest_, partners_, lit_medians_, background_;
};

// The background pixels sampled from a stack's mask (CV_8UC1, 255 at those),
// clear of the object by a margin; empty when there is no mask or no background.
cv::Mat background_sample_mask(const cv::Mat& mask);
// "dark frames", "black level" or "noise floor": what the stack subtracted.
std::string shadow_threshold_source(const ImageStack& stack);

// The threshold for `observations` made from `stack` (its mask, dark frames
// and black levels).
ShadowThreshold estimate_shadow_threshold(const ImageStack& stack, const Observations& observations);
// The same from the observations alone (no background, no dark frames known).
ShadowThreshold estimate_shadow_threshold(const Observations& observations);

}  // namespace lightstage
