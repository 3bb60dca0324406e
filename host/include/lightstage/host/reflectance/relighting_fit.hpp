#pragma once
// The per-pixel reflectance that relighting uses, fitted once the normals are
// known. A bi-polynomial solve finds its normal from the darkest T_low part of
// each pixel's lit values, so its coefficients describe that part only and
// extrapolate wildly towards the highlights and grazing lights they never saw.
// Here, at the solved normal, the coefficients are refitted to every lit,
// unsaturated observation, held towards the object's own BRDF:
//   ρ_p(x, y) = Σ c_p,t x^i y^j,    x = n·h, y = l·h   (bipolynomial_model.hpp)
//   c_p = argmin Σ_j ((n·l_j) b(x_j, y_j)ᵀ c − v_j)² + Σ_t λ_t D_t (c_t − s_p g_t)²
// g: the object BRDF, one least-squares fit over the pixels of their values
// divided by each pixel's Lambertian albedo; s_p: the pixel's scale of it;
// D_t: the mean over pixels of Σ_j ((n·l_j) b_t)², so that λ = 1 weighs the
// prior as much as an average pixel's data. Where a pixel's lights leave terms
// undetermined (few lit lights, a narrow range of x or y) the prior fills
// them in, instead of the noise. λ is chosen by cross-validation over the
// lights (every folds-th light held out in turn, on a sample of pixels),
// scoring the relit value max(ρ, 0)·(n·l) as `relight` renders it.
// A sharp highlight is beyond any polynomial of this order, so the model may
// add one term: ρ += c_lobe · D(n·h), D a Beckmann-shaped lobe of one width m
// for the whole object (bipolynomial_model.hpp specular_lobe), its weight
// held to the object's with its own λ. The same cross-validation picks m and
// that λ, and keeps the lobe only when it predicts the held-out lights better
// than the polynomial alone by more than min_lobe_gain.

#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/solvers/pixel_observations.hpp"

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <array>
#include <optional>
#include <vector>

namespace lightstage {

struct RelightingFitOptions {
  int order = 2;                 // bi-polynomial order of the coefficients written
  double shadow_threshold = 0;   // values at or below it are not lit (the solve's threshold)
  std::optional<double> lambda;  // fixed prior weight (and no lobe); empty = cross-validation
  std::vector<double> lambdas;   // the candidates (empty = a default grid from 0 to 1000)
  int folds = 8;                 // cross-validation folds over the lights
  int sample_pixels = 4000;      // pixels the object BRDF and the cross-validation use (evenly spread)
  bool specular_lobe = true;     // try the lobe
  std::vector<double> lobe_widths = {0.03, 0.05, 0.08, 0.12, 0.2};  // candidates for m
  std::vector<double> lobe_lambdas = {0.01, 1, 100, 1e4};           // candidates for the lobe's λ
  double min_lobe_gain = 0.01;  // relative cross-validated error the lobe must save
  int threads = 0;              // 0 = hardware concurrency

  void check() const;  // throws InputError naming the field and value
};

struct RelightingFit {
  // CV_32FC(k), or CV_32FC(k + 1) with the lobe's weight last: per-pixel
  // coefficients where solved, else 0 (fit_relighting_brdf; empty from
  // fit_relighting_model).
  cv::Mat coefficients;
  int order = 2;                // of the bi-polynomial
  Eigen::VectorXd object_brdf;  // g (the lobe's weight last)
  Eigen::VectorXd penalty;      // λ_t D_t per term
  double lambda = 0;            // the weight used
  double lobe_width = 0;        // m; 0 = no lobe
  double lobe_lambda = 0;       // the lobe weight's λ
  // Cross-validated relative RMSE of the relit held-out values per candidate
  // λ, then per lobe candidate {m, its λ, error} (empty when λ was fixed).
  std::vector<std::pair<double, double>> validation;
  std::vector<std::array<double, 3>> lobe_validation;
  std::size_t pixels = 0;  // pixels refitted so far (the others kept the fallback)

  // For the solve's reflectance description ("fit").
  nlohmann::json to_json() const;
};

// The refit in parts, for observations met a band of rows at a time (a
// stack read in bands): the solved pixels counted, a sample of them gathered
// band by band, the object-wide model (g, λ, the lobe) fitted to the sample,
// then each band's pixels refitted. The parts give what fit_relighting_brdf
// gives the whole image at once, float for float.

// The pixels of `normals` (CV_32FC3) / `solved` (CV_8UC1) that are refitted:
// solved, with a finite normal of about unit length.
std::size_t count_refittable_pixels(const cv::Mat& normals, const cv::Mat& solved);

// At most options.sample_pixels of the refittable pixels, evenly spread over
// them in scan order: their observations and normals.
class RelightingSample {
 public:
  // `refittable_pixels`: those of the whole image.
  RelightingSample(std::size_t refittable_pixels, const RelightingFitOptions& options);
  // The whole image's pixels, or one band's after another, top to bottom.
  void add(const Observations& observations, const cv::Mat& normals, const cv::Mat& solved);

  std::size_t size() const { return pixels_.size(); }
  const PixelObservations& pixel(std::size_t i) const { return pixels_[i]; }
  const Eigen::Vector3d& normal(std::size_t i) const { return normals_[i]; }
  std::size_t total() const { return total_; }
  std::size_t seen() const { return seen_; }

 private:
  std::size_t total_ = 0;
  std::size_t limit_ = 0;
  std::size_t seen_ = 0;  // refittable pixels added so far
  std::vector<PixelObservations> pixels_;
  std::vector<Eigen::Vector3d> normals_;
};

// The object-wide part from every pixel's sample: g, λ (cross-validated
// unless fixed), the lobe. Throws InputError when the sample did not see
// every pixel it was made for.
RelightingFit fit_relighting_model(const RelightingSample& sample, const RelightingFitOptions& options);

// The refitted coefficients of every refittable pixel of `observations`
// (the whole image's or a band's), by `fit`'s model; adds the pixels
// refitted to fit.pixels. `fallback` as below.
cv::Mat refit_coefficients(const Observations& observations, const cv::Mat& normals, const cv::Mat& solved,
                           RelightingFit& fit, const RelightingFitOptions& options, const cv::Mat& fallback);

// Refits the coefficients of every solved pixel of `normals` (CV_32FC3) /
// `solved` (CV_8UC1) from `observations`. Pixels without a lit observation
// in front of their normal keep `fallback`'s polynomial (the solver's
// coefficients, CV_32FC((order+1)²); empty = zeros) and no lobe. Throws
// InputError when the maps do not match the observations.
RelightingFit fit_relighting_brdf(const Observations& observations, const cv::Mat& normals,
                                  const cv::Mat& solved, const RelightingFitOptions& options,
                                  const cv::Mat& fallback = {});

}  // namespace lightstage
