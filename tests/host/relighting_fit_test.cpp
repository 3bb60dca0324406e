// The relighting BRDF refit (reflectance/relighting_fit.hpp): exact on data
// the model can represent, better than a bi-polynomial solve's own T_low
// coefficients at lights it never saw, and a prior weight chosen from the data.
#include "lightstage/host/reflectance/relighting_fit.hpp"
#include "lightstage/common/error.hpp"
#include "lightstage/host/reflectance/bipolynomial_model.hpp"
#include "lightstage/host/solvers/bipolynomial.hpp"
#include "reflectance_scene.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace lightstage {
namespace {

using testing::grid_normal;
using testing::hemisphere_lights;

Observations with_lights(const Observations& all, const std::vector<int>& keep) {
  Observations out = all;
  out.lights.resize(static_cast<Eigen::Index>(keep.size()), 3);
  out.intensities.resize(all.intensities.rows(), static_cast<Eigen::Index>(keep.size()));
  out.saturated.resize(all.saturated.rows(), static_cast<Eigen::Index>(keep.size()));
  for (std::size_t k = 0; k < keep.size(); ++k) {
    const auto c = static_cast<Eigen::Index>(k);
    out.lights.row(c) = all.lights.row(keep[k]);
    out.intensities.col(c) = all.intensities.col(keep[k]);
    out.saturated.col(c) = all.saturated.col(keep[k]);
  }
  return out;
}

// ‖relit − photo‖ / ‖photo‖ over every pixel at the lights `held`, relit as
// `relight` renders: max(ρ(n·h, l·h), 0) · max(n·l, 0), ρ with the lobe when
// lobe_width > 0.
double held_out_error(const Observations& all, const std::vector<int>& held, const cv::Mat& normals,
                      const cv::Mat& coefficients, int order, double lobe_width = 0) {
  const int terms = coefficients.channels();
  EXPECT_EQ(terms, bipolynomial_term_count(order) + (lobe_width > 0 ? 1 : 0));
  double error = 0, energy = 0;
  for (std::size_t p = 0; p < all.pixel_count(); ++p) {
    const cv::Point& at = all.pixels[p];
    const cv::Vec3f v = normals.at<cv::Vec3f>(at);
    const Vec3 n = Vec3(v[0], v[1], v[2]).normalized();
    const float* c = coefficients.ptr<float>(at.y) + static_cast<std::ptrdiff_t>(at.x) * terms;
    for (const int j : held) {
      const Vec3 l = all.lights.row(j).transpose().normalized();
      const Vec3 h = (l + Vec3::UnitZ()).normalized();
      const double relit =
          evaluate_relighting_brdf(order, lobe_width, c, n.dot(h), l.dot(h)) * std::max(n.dot(l), 0.0);
      const double photo = all.intensities(static_cast<Eigen::Index>(p), j);
      error += (relit - photo) * (relit - photo);
      energy += photo * photo;
    }
  }
  return std::sqrt(error / energy);
}

cv::Mat all_solved(cv::Size size) { return cv::Mat(size, CV_8UC1, cv::Scalar::all(255)); }

// Every `every`-th light (from the 4th) held out; the observations of the rest.
struct HeldOut {
  Observations fit;
  std::vector<int> held;
};

HeldOut hold_out(const Observations& all, int every) {
  std::vector<int> fit;
  HeldOut out;
  for (int j = 0; j < all.lights.rows(); ++j) (j % every == 3 % every ? out.held : fit).push_back(j);
  out.fit = with_lights(all, fit);
  return out;
}

// Two materials with different biquadratic BRDFs (left and right halves), so
// that the object prior is wrong for both and only λ = 0 is exact.
testing::ReflectanceScene biquadratic_scene(const Eigen::MatrixX3d& lights, cv::Size size,
                                            const Eigen::VectorXd& left, const Eigen::VectorXd& right) {
  testing::ReflectanceScene scene;
  Observations& obs = scene.observations;
  obs.size = size;
  obs.mask = cv::Mat(size, CV_8UC1, cv::Scalar::all(255));
  obs.lights = lights;
  obs.intensities.resize(size.area(), lights.rows());
  obs.saturated = FlagMatrix::Constant(size.area(), lights.rows(), false);
  scene.truth = cv::Mat(size, CV_32FC3);
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      const auto p = static_cast<Eigen::Index>(obs.pixels.size());
      obs.pixels.emplace_back(x, y);
      const Vec3 n = grid_normal(x, y, size.width, size.height);
      scene.truth.at<cv::Vec3f>(y, x) =
          cv::Vec3f(static_cast<float>(n.x()), static_cast<float>(n.y()), static_cast<float>(n.z()));
      const double albedo = 0.3 + 0.5 * (x + y) / static_cast<double>(size.width + size.height);
      const Eigen::VectorXd& c = x < size.width / 2 ? left : right;
      for (Eigen::Index j = 0; j < lights.rows(); ++j) {
        const Vec3 l = lights.row(j).transpose();
        obs.intensities(p, j) =
            static_cast<float>(albedo * evaluate_bipolynomial(2, c, n, l) * std::max(n.dot(l), 0.0));
      }
    }
  }
  return scene;
}

TEST(RelightingFit, RecoversBiquadraticReflectanceExactly) {
  Eigen::VectorXd left(9), right(9);
  left << 0.9, 0.0, 0.1, 0.2, 0.0, 0.0, 0.3, 0.0, 0.0;
  right << 0.6, 0.1, 0.0, -0.2, 0.1, 0.0, 0.8, -0.1, 0.0;
  const Eigen::MatrixX3d lights = hemisphere_lights(60, 7, 0.2);
  const auto scene = biquadratic_scene(lights, cv::Size(16, 10), left, right);
  RelightingFitOptions options;
  options.order = 2;
  const RelightingFit fit =
      fit_relighting_brdf(scene.observations, scene.truth, all_solved(scene.observations.size), options);
  EXPECT_EQ(fit.pixels, 160u);
  EXPECT_EQ(fit.lobe_width, 0) << "a lobe on data without a highlight";
  // Only λ = 0 is exact on two materials: the validation must find it.
  EXPECT_LE(fit.lambda, 1e-3);
  ASSERT_FALSE(fit.validation.empty());
  EXPECT_LT(fit.validation.front().second, 1e-4);
  EXPECT_GT(fit.validation.back().second, 10 * fit.validation.front().second);
  std::vector<int> every(static_cast<std::size_t>(lights.rows()));
  for (int j = 0; j < lights.rows(); ++j) every[static_cast<std::size_t>(j)] = j;
  EXPECT_LT(held_out_error(scene.observations, every, scene.truth, fit.coefficients, 2), 1e-3);
}

// A Cook–Torrance material with noise: a bi-polynomial solve's T_low
// coefficients relight lights it did not see badly (they never saw the
// highlight); the refit at its normals relights them well.
TEST(RelightingFit, PredictsUnseenLightsFarBetterThanTheSolversOwnCoefficients) {
  const Eigen::MatrixX3d lights = hemisphere_lights(96, 11, 0.15);
  const auto scene =
      testing::make_reflectance_scene("cook-torrance:roughness=0.3,ks=0.4", lights, 24, 16, 0.02, 5);
  const auto [fit_obs, held] = hold_out(scene.observations, 8);
  BiPolynomialOptions solver;
  solver.order = 2;
  solver.shadow_threshold = 1e-3;
  const SolveResult solved = solve_bipolynomial(fit_obs, solver);
  RelightingFitOptions options;
  options.order = 2;
  options.shadow_threshold = solver.shadow_threshold;
  const RelightingFit refit = fit_relighting_brdf(fit_obs, solved.normals, solved.solved, options);
  const double own = held_out_error(scene.observations, held, solved.normals, solved.coefficients, 2);
  const double refitted =
      held_out_error(scene.observations, held, solved.normals, refit.coefficients, 2, refit.lobe_width);
  RecordProperty("own_coefficients", std::to_string(own));
  RecordProperty("refitted", std::to_string(refitted));
  EXPECT_LT(refitted, 0.5 * own) << "own " << own << ", refitted " << refitted;
  EXPECT_LT(refitted, 0.08) << "own " << own;
}

// A sharp highlight (Cook–Torrance roughness 0.1) is beyond the polynomial:
// the lobe is chosen, near the material's width, and relights the lights
// the fit never saw better than the polynomial alone.
TEST(RelightingFit, ASharpHighlightGetsTheSpecularLobe) {
  const Eigen::MatrixX3d lights = hemisphere_lights(120, 13, 0.15);
  const auto scene =
      testing::make_reflectance_scene("cook-torrance:roughness=0.1,ks=0.5", lights, 40, 24, 0.01, 5);
  const auto [fit_obs, held] = hold_out(scene.observations, 8);
  RelightingFitOptions options;
  options.order = 2;
  options.shadow_threshold = 1e-3;
  const RelightingFit lobe = fit_relighting_brdf(fit_obs, scene.truth, all_solved(fit_obs.size), options);
  options.specular_lobe = false;
  const RelightingFit plain = fit_relighting_brdf(fit_obs, scene.truth, all_solved(fit_obs.size), options);
  ASSERT_GT(lobe.lobe_width, 0);
  EXPECT_EQ(lobe.coefficients.channels(), 10);
  EXPECT_EQ(plain.lobe_width, 0);
  EXPECT_EQ(plain.coefficients.channels(), 9);
  const double with_lobe =
      held_out_error(scene.observations, held, scene.truth, lobe.coefficients, 2, lobe.lobe_width);
  const double without = held_out_error(scene.observations, held, scene.truth, plain.coefficients, 2);
  RecordProperty("lobe_width", std::to_string(lobe.lobe_width));
  RecordProperty("with_lobe", std::to_string(with_lobe));
  RecordProperty("without", std::to_string(without));
  EXPECT_LT(with_lobe, 0.8 * without) << "m " << lobe.lobe_width;
}

// Twelve lights, noisy, two materials: few observations per term, so the
// prior must carry weight, and the chosen weight must beat none on lights
// the fit never saw.
TEST(RelightingFit, FewLightsLeanOnTheObjectBrdf) {
  Eigen::VectorXd left(9), right(9);
  left << 0.9, 0.0, 0.1, 0.2, 0.0, 0.0, 0.3, 0.0, 0.0;
  right << 0.8, 0.1, 0.0, -0.1, 0.1, 0.0, 0.4, -0.1, 0.0;
  const Eigen::MatrixX3d lights = hemisphere_lights(24, 5, 0.3);
  auto scene = biquadratic_scene(lights, cv::Size(20, 12), left, right);
  std::mt19937 rng(9);
  std::normal_distribution<float> noise(0.f, 0.02f);
  for (Eigen::Index i = 0; i < scene.observations.intensities.size(); ++i)
    scene.observations.intensities.data()[i] =
        std::max(0.f, scene.observations.intensities.data()[i] + noise(rng));
  const auto [fit_obs, held] = hold_out(scene.observations, 2);
  RelightingFitOptions options;
  options.order = 2;
  options.shadow_threshold = 0.01;
  const RelightingFit chosen = fit_relighting_brdf(fit_obs, scene.truth, all_solved(fit_obs.size), options);
  options.lambda = 0;
  const RelightingFit none = fit_relighting_brdf(fit_obs, scene.truth, all_solved(fit_obs.size), options);
  EXPECT_GT(chosen.lambda, 0);
  const double e_chosen =
      held_out_error(scene.observations, held, scene.truth, chosen.coefficients, 2, chosen.lobe_width);
  const double e_none = held_out_error(scene.observations, held, scene.truth, none.coefficients, 2);
  RecordProperty("chosen", std::to_string(e_chosen));
  RecordProperty("none", std::to_string(e_none));
  EXPECT_LT(e_chosen, 0.9 * e_none) << "λ " << chosen.lambda;
}

TEST(RelightingFit, PixelsWithNothingLitKeepTheFallback) {
  Eigen::VectorXd c(9);
  c << 0.9, 0.0, 0.1, 0.2, 0.0, 0.0, 0.3, 0.0, 0.0;
  auto scene = biquadratic_scene(hemisphere_lights(40, 3, 0.2), cv::Size(8, 6), c, c);
  scene.observations.intensities.row(5).setZero();  // pixel (5, 0): every light a shadow
  const cv::Mat fallback =
      cv::Mat(6, 8 * 9, CV_32FC1, cv::Scalar::all(0.25)).reshape(9);  // OpenCV fills at most 4 channels
  RelightingFitOptions options;
  options.shadow_threshold = 1e-3;
  const RelightingFit fit = fit_relighting_brdf(scene.observations, scene.truth,
                                                all_solved(scene.observations.size), options, fallback);
  EXPECT_EQ(fit.pixels, 47u);
  const int terms = fit.coefficients.channels();
  const float* kept = fit.coefficients.ptr<float>(0) + 5 * terms;
  for (int t = 0; t < 9; ++t) EXPECT_EQ(kept[t], 0.25f) << t;
  if (terms == 10) {
    EXPECT_EQ(kept[9], 0.f);
  }
  // Its neighbour is refitted: it relights its own lights (exact data).
  const Vec3 n = grid_normal(4, 0, 8, 6);
  const float* refitted = fit.coefficients.ptr<float>(0) + 4 * terms;
  for (Eigen::Index j = 0; j < scene.observations.lights.rows(); ++j) {
    const Vec3 l = scene.observations.lights.row(j).transpose();
    const Vec3 h = (l + Vec3::UnitZ()).normalized();
    const double relit =
        evaluate_relighting_brdf(2, fit.lobe_width, refitted, n.dot(h), l.dot(h)) * std::max(n.dot(l), 0.0);
    EXPECT_NEAR(relit, scene.observations.intensities(4, j), 1e-3) << j;
  }
  EXPECT_THROW(fit_relighting_brdf(scene.observations, scene.truth, all_solved(scene.observations.size),
                                   options, cv::Mat(2, 2, CV_32FC(9))),
               InputError);
}

TEST(RelightingFit, TheLobeIsOneAtItsPeakAndZeroFarDownItsTail) {
  EXPECT_DOUBLE_EQ(specular_lobe(1.0, 0.05), 1.0);
  EXPECT_EQ(specular_lobe(0.0, 0.05), 0.0);
  EXPECT_EQ(specular_lobe(1e-200, 0.05), 0.0);  // no 0/0
  EXPECT_EQ(specular_lobe(-0.5, 0.05), 0.0);
  EXPECT_NEAR(specular_lobe(std::cos(0.05), 0.05),
              std::exp(-std::pow(std::tan(0.05) / 0.05, 2)) / std::pow(std::cos(0.05), 4), 1e-12);
  // The peak stays at n·h = 1 up to the widest width allowed.
  EXPECT_LE(specular_lobe(0.95, kMaxLobeWidth), 1.0);
}

TEST(RelightingFit, BadOptionsAndMapsAreNamed) {
  const Eigen::MatrixX3d lights = hemisphere_lights(20, 3, 0.2);
  const auto scene = testing::make_reflectance_scene("lambert", lights, 6, 4);
  const cv::Mat solved = all_solved(scene.observations.size);
  RelightingFitOptions options;
  options.folds = 1;
  EXPECT_THROW(
      {
        try {
          fit_relighting_brdf(scene.observations, scene.truth, solved, options);
        } catch (const InputError& e) {
          EXPECT_NE(std::string(e.what()).find("folds"), std::string::npos) << e.what();
          throw;
        }
      },
      InputError);
  options = {};
  options.order = 4;
  EXPECT_THROW(fit_relighting_brdf(scene.observations, scene.truth, solved, options), InputError);
  options = {};
  options.lambda = -1;
  EXPECT_THROW(fit_relighting_brdf(scene.observations, scene.truth, solved, options), InputError);
  options = {};
  EXPECT_THROW(fit_relighting_brdf(scene.observations, scene.truth, cv::Mat(2, 2, CV_8UC1), options),
               InputError);
}

// Rows [y0, y0 + rows) of observations of every pixel (distant lights), as a stack read in bands gives them.
Observations band_of(const Observations& all, int y0, int rows) {
  Observations band;
  band.size = {all.size.width, rows};
  band.mask = all.mask.empty() ? cv::Mat() : all.mask.rowRange(y0, y0 + rows).clone();
  band.lights = all.lights;
  band.origin = {0, y0};
  band.whole_size = all.size;
  std::vector<Eigen::Index> kept;
  for (std::size_t p = 0; p < all.pixel_count(); ++p) {
    const cv::Point at = all.pixels[p];
    if (at.y < y0 || at.y >= y0 + rows) continue;
    if (band.pixels.empty()) band.first_pixel = p;
    band.pixels.emplace_back(at.x, at.y - y0);
    kept.push_back(static_cast<Eigen::Index>(p));
  }
  band.intensities = all.intensities(kept, Eigen::all);
  if (all.saturated.size() != 0) band.saturated = all.saturated(kept, Eigen::all);
  return band;
}

TEST(RelightingFit, FittedBandByBandItGivesTheWholeImagesFitFloatForFloat) {
  Eigen::VectorXd c(9);
  c << 0.9, 0.0, 0.1, 0.2, 0.0, 0.0, 0.3, 0.0, 0.0;
  const auto scene = biquadratic_scene(hemisphere_lights(40, 3, 0.2), cv::Size(9, 7), c, 0.5 * c);
  cv::Mat solved = all_solved(scene.observations.size);
  solved.at<std::uint8_t>(2, 3) = 0;  // unsolved pixels are neither sampled nor refitted
  RelightingFitOptions options;
  options.sample_pixels = 20;  // fewer than the pixels: an evenly spread sample across the bands
  const RelightingFit whole = fit_relighting_brdf(scene.observations, scene.truth, solved, options);

  const int band_rows = 3;
  RelightingSample sample(count_refittable_pixels(scene.truth, solved), options);
  EXPECT_EQ(sample.total(), 62u);
  for (int y0 = 0; y0 < 7; y0 += band_rows) {
    const int rows = std::min(band_rows, 7 - y0);
    sample.add(band_of(scene.observations, y0, rows), scene.truth.rowRange(y0, y0 + rows),
               solved.rowRange(y0, y0 + rows));
  }
  EXPECT_EQ(sample.size(), 20u);
  RelightingFit banded = fit_relighting_model(sample, options);
  cv::Mat coefficients;
  for (int y0 = 0; y0 < 7; y0 += band_rows) {
    const int rows = std::min(band_rows, 7 - y0);
    coefficients.push_back(refit_coefficients(band_of(scene.observations, y0, rows),
                                              scene.truth.rowRange(y0, y0 + rows),
                                              solved.rowRange(y0, y0 + rows), banded, options, {}));
  }
  EXPECT_EQ(banded.to_json(), whole.to_json());
  ASSERT_EQ(coefficients.type(), whole.coefficients.type());
  EXPECT_EQ(cv::norm(coefficients.reshape(1), whole.coefficients.reshape(1), cv::NORM_INF), 0);

  // A sample not shown every pixel it was made for is refused, as is one shown more.
  RelightingSample partial(62, options);
  partial.add(band_of(scene.observations, 0, 3), scene.truth.rowRange(0, 3), solved.rowRange(0, 3));
  EXPECT_THROW(fit_relighting_model(partial, options), InputError);
  RelightingSample small(10, options);
  EXPECT_THROW(small.add(scene.observations, scene.truth, solved), InputError);
}

}  // namespace
}  // namespace lightstage
