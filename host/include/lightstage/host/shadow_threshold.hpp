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

#include <cstddef>
#include <string>

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
  // "shadow threshold 0.0123 (noise floor: level 0.0041, noise 0.0027)".
  std::string describe() const;
};

// The threshold for `observations` made from `stack` (its mask, dark frames
// and black levels).
ShadowThreshold estimate_shadow_threshold(const ImageStack& stack, const Observations& observations);
// The same from the observations alone (no background, no dark frames known).
ShadowThreshold estimate_shadow_threshold(const Observations& observations);

}  // namespace lightstage
