#pragma once
// Photometric stereo under unknown general lighting with a shape prior
// (dissertation Chapter 4, Algorithm 3; ALGORITHMS.md §4). Lambertian
// surface, lighting anything (area lights, ambient, an environment), camera
// gain and response unknown and possibly different per image: images are
// used as the camera gave them.
//  1. Rank-k SVD of the observations I (pixels × images): S̃ = U_k Σ_k^½, the
//     shape up to a k×k ambiguity (k = 9: second-order spherical harmonics,
//     16: third order). A nonlinear response is absorbed into the lighting
//     side, I ≈ S L F (Eq. 4.5).
//  2. A (k×3) = argmin ‖G(S̃) A − G(N)‖ (Eq. 4.6), N the prior's normals, G a
//     Gaussian smoothing over the mask (normalised convolution).
//  3. A* = argmin ‖O(G(S̃) A) − O(G(N))‖ by Nelder–Mead from A (Eq. 4.7), O
//     normalising rows; handles albedo variation, which (2) cannot.
//  4. Normals N* = O(S̃ A*); albedo |S̃ A*| (relative: unknown gain).
//  5. The result never trusts the fit over the prior without evidence: with a
//     shading model S̃ ≈ ρ Y(n) B (Y second- or third-order spherical
//     harmonics; B fitted to the fit's or to the prior's normals, whichever
//     explains the images better), each pixel keeps the prior's normal unless
//     the fit's explains its images better by more than keep_prior_margin ×
//     the fit's median cost (the cost: the image residual within the rank-k
//     subspace).

#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/solvers/solve_result.hpp"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

namespace lightstage {

struct ShapePriorOptions {
  int sh_dimension = 9;              // k: 9 (order 2) or 16 (order 3)
  double smoothing_sigma = 3.0;      // G: Gaussian sigma in pixels; 0 = no smoothing
  bool refine = true;                // Eq. 4.7 after Eq. 4.6
  int max_evaluations = 6000;        // Nelder–Mead cost evaluations
  int refine_pixels = 6000;          // the refinement's cost uses at most this many pixels (evenly spread)
  double min_prior_fraction = 0.05;  // of the mask's pixels with a prior normal, or fail
  bool keep_prior = true;            // step 5
  double keep_prior_margin = 0.2;    // step 5's margin, in units of the fit's median photometric cost
  // Refinement cost evaluations done (solve_result.hpp; up to max_evaluations,
  // fewer when it converges); not part of to_json().
  SolveProgress progress;

  void check() const;  // throws InputError naming the field and value
  nlohmann::json to_json() const;
};

// `prior_normals`: CV_32FC3 (x, y, z) of the observations' image size, unit
// where `prior_valid` (CV_8UC1, empty = where nonzero) is set. Throws
// InputError when there are fewer images than k, no usable prior, or sizes
// disagree. SolveResult::parameters holds the options and the fit (costs
// before and after refinement, evaluations, singular values) and "kept_prior"
// (pixels and fraction where step 5 kept the prior's normal, the cost margin,
// which normals the shading model was fitted to).
SolveResult solve_shape_prior(const Observations& observations, const cv::Mat& prior_normals,
                              const cv::Mat& prior_valid, const ShapePriorOptions& options = {});

}  // namespace lightstage
