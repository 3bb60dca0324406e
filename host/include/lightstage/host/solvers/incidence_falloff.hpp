#pragma once
// The start of the bi-polynomial fit, with the diffuse fall-off at grazing
// incidence (beyond the dissertation; docs/solvers.md).
//
// Algorithm 2 starts from Lambert on the T_low set, and T_low keeps each
// pixel's darkest lit observations: those at grazing incidence. Real
// dielectrics (plastics, paints, the DiLiGenT ball) are darker there than
// Lambert says, because less light is transmitted into the body at grazing
// incidence (Fresnel; Wolff's diffuse model), so the Lambertian start leans
// away from the lights that see the surface most obliquely. With lights in a
// cone around the view axis the alternation cannot undo that: a radial tilt
// and a change of ρ with l·h explain the data alike (l·h depends only on the
// light's elevation), so the start decides the zenith.
//
// The start therefore fits i_j = a (t_j + κ t_j²), t_j = n·l_j: a reflectance
// that grows linearly with the cosine of incidence, ρ ∝ 1 + κ t. κ = 0 is
// Lambert. Unlike l·h, t varies along the lights of equal elevation, so a
// tilt cannot imitate κ. κ is a property of the material: it is estimated
// once per object as the median of free per-pixel fits (a, b = aκ and the
// normal by Gauss–Newton), then each pixel's start is fitted with that κ.

#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/solvers/pixel_observations.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <optional>
#include <vector>

namespace lightstage {

struct BiPolynomialOptions;

// κ is kept in this range: below −0.5 the modelled shading t + κt² would
// fall with t somewhere on [0, 1].
inline constexpr double kMinFalloff = -0.5;
inline constexpr double kMaxFalloff = 5.0;
// Fewer kept observations cannot tell t from t² (the free fit has four
// unknowns): such pixels neither vote for κ nor get the fall-off start (on 12
// lights with 6 kept it moved the start far: docs/solvers.md).
inline constexpr std::size_t kMinFalloffObservations = 10;
// Fewer voting pixels than this leave κ at 0 (the Lambertian start).
inline constexpr std::size_t kMinFalloffPixels = 50;
// Pixels the object's κ is estimated from, at most.
inline constexpr std::size_t kFalloffSamplePixels = 20000;

struct FalloffPixelFit {
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  double albedo = 0;  // a
  double kappa = 0;   // the fixed κ, or the fitted b / a
};

// Fits the observations `kept` of `pixel` from the initial normal `start`:
// with `kappa` set, a and the normal (κ fixed); without it, a, b and the
// normal (Gauss–Newton with variable projection, at most 30 steps). Returns
// nothing when the fit degenerates (coplanar lights, t and t² numerically
// indistinguishable, a ≤ 0, non-finite values) or has not converged.
std::optional<FalloffPixelFit> fit_falloff_pixel(const PixelObservations& pixel,
                                                 const std::vector<Eigen::Index>& kept,
                                                 const Eigen::Vector3d& start, std::optional<double> kappa);

struct FalloffEstimate {
  double kappa = 0;          // median of the per-pixel fits, clamped to [kMinFalloff, kMaxFalloff]
  double quartile_low = 0;   // the per-pixel fits' 25th and 75th percentiles (unclamped;
  double quartile_high = 0;  // 0 with fewer than kMinFalloffPixels fits)
  std::size_t pixels = 0;    // pixels whose free fit counted
};

// κ for the object: free fits on at most `max_pixels` (0 = all) pixels spread evenly
// over the mask, each on the T_low set that `options` selects (pixels with
// fewer than kMinFalloffObservations kept skipped). κ = 0 when fewer than
// kMinFalloffPixels pixels give a fit. The result does not depend on
// options.threads.
FalloffEstimate estimate_incidence_falloff(const Observations& observations,
                                           const BiPolynomialOptions& options,
                                           std::size_t max_pixels = kFalloffSamplePixels);

// The same gathered band by band (a stack read in bands, io/stack_bands.hpp):
// the pixels sampled are those the whole image's estimate samples, by their
// place among its `total_pixels` mask pixels (Observations::first_pixel).
class FalloffSamples {
 public:
  explicit FalloffSamples(std::size_t total_pixels, std::size_t max_pixels = kFalloffSamplePixels);
  void add(const Observations& observations, const BiPolynomialOptions& options);
  FalloffEstimate estimate() const;

 private:
  std::size_t stride_ = 1;
  std::vector<double> kappas_;
};

}  // namespace lightstage
