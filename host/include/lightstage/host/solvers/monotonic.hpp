#pragma once
// Elevation from reflectance monotonicity (dissertation Chapter 2,
// Algorithm 1; ALGORITHMS.md §2), for isotropic BRDFs with a dominant lobe
// ρ(n·h) that increases with n·h, under dense lights over the hemisphere.
// Normals are n = [cosθ cosφ, cosθ sinφ, sinθ] (θ elevation from the image
// plane, φ azimuth). Per pixel:
//  1. azimuth φ: from isotropy (Alldrin–Kriegman): the pixel's values are
//     interpolated onto view-centred rings of lights, where an isotropic BRDF
//     gives a profile symmetric about φ; φ = the most symmetric axis, on the
//     brighter side. Or φ from another method's normals.
//  2. for each hypothesised θ' (coarse grid, then a fine grid around the best):
//     y'_j = i_j / (n'·l_j); y'_j = i0 for shadows (i_j ≤ i0); y'_j = i∞ when
//     n'·l_j ≤ 0 for a lit observation; y' ← y'^γ; sort by x'_j = n'·h_j;
//     δ(θ') = Σ max(−Δy'/Δx', 0) (Eq. 2.7). θ = argmin δ.
//  3. beyond the dissertation: δ is one-sided around the true θ. Below it, lit
//     observations near the terminator go behind the hypothesised surface (or
//     their y' explodes) and δ rises steeply; above it, the diffuse part of the
//     profile stays nearly monotonic and δ barely grows — with noise it even
//     falls on average. So the argmin drifts up that plateau, and from it θ
//     descends while δ stays within (1 + plateau_tolerance) × δ_min, the noise
//     level of the best hypothesis (docs/solvers.md has the measurements).
// Outputs: normal, albedo = median of i_j / (n·l_j) over lit observations,
// residual = δ at the answer (in y'^γ units).

#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/solvers/pixel_observations.hpp"
#include "lightstage/host/solvers/solve_result.hpp"

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <vector>

namespace lightstage {

struct MonotonicOptions {
  double shadow_threshold = 1e-6;  // i0: 1e-6 on synthetic data, ~0.02 on real data (≥ 0)
  double infinity = 1e10;          // i∞
  double gamma = 5;                // y' ← y'^γ before the cost (> 0)
  double coarse_step_deg = 1.0;    // first pass over θ' ∈ [0, 90]
  double fine_step_deg = 0.1;      // second pass within ± coarse_step of the best
  // Step 3: descend from the argmin while δ ≤ (1 + this) × δ_min (1: twice
  // the best cost, which noise alone reaches); 0 = the argmin, as published.
  // Larger values help the material sweep but overshoot below the true
  // elevation on a Lambertian surface (docs/solvers.md has the sweep).
  double plateau_tolerance = 1.0;
  // > 0: refine θ and φ together around the 1-D answer (pattern search, steps
  // from this size down to fine_step_deg; then step 3 again). Beyond the
  // dissertation: it corrects an azimuth a few degrees off, but it is worse on
  // the sweep except at the strongest noise (docs/solvers.md), so off by default.
  double refine_step_deg = 0;
  int min_observations = 6;  // fewer lit observations: rejected
  // Isotropy azimuth: rings at these quantiles of the lights' angles from the
  // viewer, each with ring_samples samples, interpolated from the
  // ring_neighbours nearest lights (inverse squared angle weights).
  std::vector<double> ring_quantiles = {0.3, 0.5, 0.7};
  int ring_samples = 72;
  int ring_neighbours = 4;
  bool drop_saturated = true;
  int threads = 0;
  SolveProgress progress;  // pixels done (solve_result.hpp); not part of to_json()

  void check() const;  // throws InputError naming the field and value
  nlohmann::json to_json() const;
};

// One pixel's usable observations, compacted, and the order of the last
// hypothesis's x' (neighbouring hypotheses are nearly sorted already, so an
// insertion sort from the previous order is linear in practice).
struct MonotonicWorkspace {
  std::vector<Eigen::Vector3d> lights, halves;
  std::vector<double> values, x, y;
  std::vector<int> order;
};
// Fills the workspace from `pixel` (call once per pixel).
void prepare_monotonic(const PixelObservations& pixel, MonotonicWorkspace& workspace);
// Cost δ of one hypothesised normal (Eq. 2.7), after prepare_monotonic.
double monotonicity_cost(const Eigen::Vector3d& normal, const MonotonicOptions& options,
                         MonotonicWorkspace& workspace);

struct ElevationEstimate {
  double elevation = 0;  // radians, [0, π/2]
  double cost = 0;       // δ there (after step 3: up to (1 + plateau_tolerance) × the minimum)
};
// 1-D search of θ at a fixed azimuth (steps 2 and 3), after prepare_monotonic.
ElevationEstimate search_elevation(double azimuth, const MonotonicOptions& options,
                                   MonotonicWorkspace& workspace);

// Step 3 alone: from `start`, the lowest θ reached in fine steps with δ within
// (1 + plateau_tolerance) × start.cost; `start` itself when the tolerance is 0.
ElevationEstimate descend_plateau(const ElevationEstimate& start, double azimuth,
                                  const MonotonicOptions& options, MonotonicWorkspace& workspace);

// Optional local refinement of (θ, φ) together around an estimate: a pattern
// search on δ with steps from `step_deg` down to options.fine_step_deg, then
// step 3 at the refined azimuth. Returns the refined normal.
Eigen::Vector3d refine_normal(const Eigen::Vector3d& normal, double step_deg, const MonotonicOptions& options,
                              MonotonicWorkspace& workspace);

// Interpolation of a pixel's values onto view-centred rings of lights.
class RingInterpolation {
 public:
  // Builds the rings for `lights` (images × 3).
  RingInterpolation(const Eigen::MatrixX3d& lights, const MonotonicOptions& options);
  // φ of the symmetry axis, on the brighter side, in (−π, π].
  double azimuth(const PixelObservations& pixel) const;
  int ring_count() const { return static_cast<int>(weights_.size()); }

 private:
  int samples_;
  // Per ring, per sample: (light index, weight) of its neighbours.
  std::vector<std::vector<std::vector<std::pair<Eigen::Index, double>>>> weights_;
};

// Fraction of consecutive pairs, sorted by n·h, whose i/(n·l) does not
// decrease, over lit observations with n·l > 0 (1 = perfectly one-lobe).
double profile_monotonicity(const PixelObservations& pixel, const Eigen::Vector3d& normal,
                            double shadow_threshold);

// Every pixel. `azimuth_normals` (CV_32FC3, same size, zero = unknown): when
// given, φ comes from them wherever they hold a normal; elsewhere (and when
// empty) from isotropy.
SolveResult solve_monotonic(const Observations& observations, const MonotonicOptions& options = {},
                            const cv::Mat& azimuth_normals = {});

}  // namespace lightstage
