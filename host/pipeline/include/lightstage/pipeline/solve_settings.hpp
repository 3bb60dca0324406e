#pragma once
// Everything `solve --method NAME` can be told, for every method at once: each
// solver's Options struct plus the few settings that several methods share.
// The CLI binds its flags to these fields; library callers (the demo, the
// material sweep, Python) fill them directly. resolve() turns the shared
// settings into each method's options and checks the chosen method's.

#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/solvers/auto.hpp"
#include "lightstage/host/solvers/bipolynomial.hpp"
#include "lightstage/host/solvers/lambertian.hpp"
#include "lightstage/host/solvers/low_rank.hpp"
#include "lightstage/host/solvers/monotonic.hpp"
#include "lightstage/host/solvers/robust.hpp"
#include "lightstage/host/solvers/shape_prior.hpp"
#include "lightstage/host/solvers/sparse_regression.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <optional>
#include <string>

namespace lightstage::pipeline {

// `--method shape-prior`: the depth prior, the camera that relates it to the
// images, and the solver's options (shape_prior_method.hpp).
struct ShapePriorSettings {
  ShapePriorOptions options;
  std::string prior;        // depth PNG, PFM, EXR or PLY
  std::string intrinsics;   // K.txt of a perspective camera; empty = orthographic
  double pixel_mm = 1.0;    // orthographic pixel size in the prior's unit
  double prior_radius = 0;  // plane-PCA radius; 0 = three pixel footprints
  double png_scale = 1.0;   // depth unit per DN of a 16-bit PNG prior
};

struct SolveSettings {
  std::string method = "l2";  // a name of the registry (solve_methods.hpp)
  L2Options l2;
  RobustOptions robust;
  RpcaOptions rpca;  // the published robust family (low_rank.hpp, sparse_regression.hpp)
  L1Options l1;
  SblOptions sbl;
  MonotonicOptions monotonic;
  BiPolynomialOptions bipolynomial;
  AutoOptions automatic;
  ShapePriorSettings shape_prior;
  std::string estimator = "irls-l1";  // robust: irls-l1, ransac or none
  // monotonic: the azimuth from isotropy or another method's normals (robust:
  // better on the material sweep and the DiLiGenT ball than isotropy).
  std::string azimuth_from = "robust";
  // Settings several methods share: when set, resolve() copies them into each method's options.
  std::optional<double> shadow_threshold, t_low;
  std::optional<int> min_observations, threads, max_iterations;
  std::string falloff = "auto";  // bi-polynomial and auto: "auto" or kappa (incidence_falloff.hpp)
  RadiometryOptions radiometry;
  // --memory-limit (memory_budget.hpp): a stack whose solve would need more is solved in bands.
  std::string memory_limit = "auto";
  // A band's observations are made and solved in parts of its rows holding
  // about this many bytes of observations, one row at least (band_solver.cpp
  // says why); tests make it small to split their small bands.
  std::size_t band_part_bytes = std::size_t{24} << 20;
  // --crop X,Y,W,H: only that region of the images (from the top left) is read
  // and solved; its maps are W x H, near lights and calibration still placed
  // in the whole image. Empty: the whole image.
  std::string crop;
  bool no_clamp = false;
  bool shadow_screen = false;  // robust: RobustOptions::screen_cast_shadows

  // Copies the shared settings into the methods' options and checks the
  // chosen method's (a bad value fails before any input is read, naming its
  // flag). Throws InputError.
  void resolve();
  // Without --shadow-threshold: the threshold estimated from the data
  // (shadow_threshold.hpp) for every method but l2, whose default keeps every
  // observation because that is the published least-squares baseline
  // (DiLiGenT's 4.10 deg on the ball) it reproduces.
  void use_data_shadow_threshold(double value);
  // Whether the solve drops observations at or below a shadow threshold:
  // every method but l2 without --shadow-threshold. That l2 and its
  // confidence take every positive observation, so nothing it writes but
  // summary.json's record of the estimate depends on the data's threshold
  // (a stack solved in bands then needs no pass to estimate it first).
  bool drops_shadows() const { return method != "l2" || shadow_threshold.has_value(); }
  // Gives every method's options the same progress report (solve_result.hpp).
  void set_progress(const SolveProgress& progress);
};

// "X,Y,W,H" (X, Y >= 0, W, H > 0) as a rectangle; empty text gives an empty
// one. Throws InputError naming --crop.
cv::Rect parse_crop(const std::string& text);

// The region of an `image`-sized stack a solve reads: --crop, checked to lie
// inside it (InputError naming --crop, the size and `input`), else the whole image.
cv::Rect solve_region(const SolveSettings& settings, cv::Size image, const std::filesystem::path& input);

// The bi-polynomial start's fall-off: "auto" (estimated from the object, nullopt)
// or a number in [kMinFalloff, kMaxFalloff]; throws InputError naming --falloff.
std::optional<double> parse_falloff(const std::string& text);

}  // namespace lightstage::pipeline
