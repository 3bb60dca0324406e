#include "lightstage/pipeline/solve_settings.hpp"

#include "lightstage/pipeline/memory_budget.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/pipeline/solve_methods.hpp"

#include <charconv>

namespace lightstage::pipeline {

std::optional<double> parse_falloff(const std::string& text) {
  if (text == "auto") return std::nullopt;
  double value = 0;
  const char* begin = text.data() + (text.starts_with('+') ? 1 : 0);  // from_chars takes no '+'
  const char* end = text.data() + text.size();
  const auto [at, error] = std::from_chars(begin, end, value);
  if (begin == end || error != std::errc{} || at != end || !(value >= kMinFalloff && value <= kMaxFalloff))
    fail("--falloff: expected 'auto' or a number in [{}, {}], got '{}'", kMinFalloff, kMaxFalloff, text);
  return value;
}

cv::Rect parse_crop(const std::string& text) {
  if (text.empty()) return {};
  int values[4] = {0, 0, 0, 0};
  const char* at = text.data();
  const char* end = text.data() + text.size();
  for (int i = 0; i < 4; ++i) {
    const auto [next, error] = std::from_chars(at, end, values[i]);
    const bool last = i == 3;
    if (error != std::errc{} || next == at || (last ? next != end : (next == end || *next != ',')))
      fail("--crop '{}': expected X,Y,W,H in pixels (e.g. 1200,800,2000,1500)", text);
    at = next + (last ? 0 : 1);
  }
  if (values[0] < 0 || values[1] < 0 || values[2] <= 0 || values[3] <= 0)
    fail("--crop '{}': X and Y must be 0 or more, W and H more than 0", text);
  return {values[0], values[1], values[2], values[3]};
}

cv::Rect solve_region(const SolveSettings& settings, cv::Size image, const std::filesystem::path& input) {
  const cv::Rect whole({0, 0}, image);
  const cv::Rect crop = parse_crop(settings.crop);
  if (crop.empty()) return whole;
  if ((crop & whole) != crop)
    fail("--crop {}: reaches outside the {}x{} images of {}", settings.crop, image.width, image.height,
         input.string());
  return crop;
}

void SolveSettings::set_progress(const SolveProgress& progress) {
  l2.progress = robust.progress = rpca.progress = l1.progress = sbl.progress = monotonic.progress =
      bipolynomial.progress = automatic.progress = progress;
  shape_prior.options.progress = progress;
}

void SolveSettings::use_data_shadow_threshold(double value) {
  robust.shadow_threshold = rpca.shadow_threshold = l1.shadow_threshold = sbl.shadow_threshold =
      monotonic.shadow_threshold = bipolynomial.shadow_threshold = value;
  automatic.monotonic.shadow_threshold = automatic.bipolynomial.shadow_threshold = value;
}

void SolveSettings::resolve() {
  find_solve_method(method);  // names the known methods when unknown
  parse_memory_limit(memory_limit);
  parse_crop(crop);
  if (!crop.empty() && method == "shape-prior")
    fail("--crop: shape-prior's depth prior covers the whole image; crop the stack and its prior instead");
  radiometry.clamp_to_one = !no_clamp;
  robust.estimator = parse_robust_estimator(estimator);
  robust.screen_cast_shadows = shadow_screen;
  if (azimuth_from != "isotropy") find_solve_method(azimuth_from);
  auto& a = automatic;
  if (shadow_threshold) {
    l2.shadow_threshold = *shadow_threshold;
    robust.shadow_threshold = monotonic.shadow_threshold = bipolynomial.shadow_threshold = *shadow_threshold;
    rpca.shadow_threshold = l1.shadow_threshold = sbl.shadow_threshold = *shadow_threshold;
    a.monotonic.shadow_threshold = a.bipolynomial.shadow_threshold = *shadow_threshold;
  }
  if (t_low) l2.t_low = robust.t_low = bipolynomial.t_low = a.bipolynomial.t_low = *t_low;
  if (min_observations)
    l2.min_observations = robust.min_observations = monotonic.min_observations = rpca.min_observations =
        l1.min_observations = sbl.min_observations = *min_observations;
  if (max_iterations) bipolynomial.max_iterations = a.bipolynomial.max_iterations = *max_iterations;
  bipolynomial.falloff = a.bipolynomial.falloff = parse_falloff(falloff);
  a.monotonic.gamma = monotonic.gamma;
  a.monotonic.plateau_tolerance = monotonic.plateau_tolerance;
  if (threads) {
    l2.threads = robust.threads = monotonic.threads = bipolynomial.threads = a.threads = *threads;
    rpca.threads = l1.threads = sbl.threads = *threads;
  }
  // Only the chosen method's options are checked here: l2 takes
  // --shadow-threshold -1, which the others refuse.
  if (method == "monotonic") monotonic.check();
  if (method == "bilinear" || method == "biquadratic" || method == "bicubic") bipolynomial.check();
  if (method == "auto") a.check();
  if (method == "rpca") rpca.check();
  if (method == "l1") l1.check();
  if (method == "sbl") sbl.check();
}

}  // namespace lightstage::pipeline
