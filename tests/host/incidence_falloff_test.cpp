// The bi-polynomial start with the object's incidence fall-off
// (incidence_falloff.hpp): exact recovery on its own model, κ = 0 where there
// is no fall-off, and the gain on a dielectric (Wolff's diffuse) under lights
// in a cone, the case the Lambertian start gets wrong.
#include "lightstage/host/solvers/incidence_falloff.hpp"
#include "lightstage/common/geometry.hpp"
#include "lightstage/host/eval/angular_error.hpp"
#include "lightstage/host/solvers/auto.hpp"
#include "lightstage/host/solvers/bipolynomial.hpp"
#include "lightstage/testing/errors.hpp"
#include "reflectance_scene.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

namespace lightstage {
namespace {

using testing::error_of;
using testing::hemisphere_lights;
using testing::make_reflectance_scene;

// Lights within 43° of the view axis, DiLiGenT's span.
constexpr double kConeZ = 0.7314;  // cos 43°

double mean_error(const SolveResult& result, const testing::ReflectanceScene& scene) {
  const auto stats = angular_error(result.normals, scene.truth, scene.observations.mask).stats;
  EXPECT_EQ(stats.missing, 0u) << result.summary.message;
  return stats.mean;
}

double angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return deg_from_rad(std::atan2(a.cross(b).norm(), a.dot(b)));
}

TEST(IncidenceFalloff, PixelFitRecoversItsOwnModelExactly) {
  const Eigen::MatrixX3d lights = hemisphere_lights(40, 11, kConeZ);
  const Eigen::Vector3d truth = direction_from_elevation_azimuth(rad_from_deg(50), rad_from_deg(30));
  const double a = 0.6, kappa = 0.45;
  PixelObservations pixel;
  pixel.lights = lights;
  pixel.values.resize(lights.rows());
  pixel.usable.assign(static_cast<std::size_t>(lights.rows()), 1);
  std::vector<Eigen::Index> kept;
  for (Eigen::Index j = 0; j < lights.rows(); ++j) {
    const double t = truth.dot(lights.row(j).transpose());
    pixel.values(j) = a * (t + kappa * t * t);
    if (t > 0) kept.push_back(j);
  }
  ASSERT_GT(kept.size(), 20u);
  // From a start 8° off, free and with κ given.
  const Eigen::Vector3d start = direction_from_elevation_azimuth(rad_from_deg(42), rad_from_deg(34));
  const auto free = fit_falloff_pixel(pixel, kept, start, std::nullopt);
  ASSERT_TRUE(free.has_value());
  EXPECT_LT(angle_deg(free->normal, truth), 1e-6);
  EXPECT_NEAR(free->kappa, kappa, 1e-6);
  EXPECT_NEAR(free->albedo, a, 1e-6);
  const auto fixed = fit_falloff_pixel(pixel, kept, start, kappa);
  ASSERT_TRUE(fixed.has_value());
  EXPECT_LT(angle_deg(fixed->normal, truth), 1e-6);
  EXPECT_EQ(fixed->kappa, kappa);
  // With the wrong κ (Lambert) the normal is off: the fall-off is not a tilt.
  const auto lambert = fit_falloff_pixel(pixel, kept, start, 0.0);
  ASSERT_TRUE(lambert.has_value());
  EXPECT_GT(angle_deg(lambert->normal, truth), 0.5);
  // Too few observations for the free model.
  const std::vector<Eigen::Index> four(kept.begin(), kept.begin() + 4);
  EXPECT_FALSE(fit_falloff_pixel(pixel, four, start, std::nullopt).has_value());
}

TEST(IncidenceFalloff, LambertianSurfacesEstimateNoFalloffAndKeepThePublishedStart) {
  for (const char* material : {"lambert", "cook-torrance:roughness=0.3,ks=0.5"}) {
    const auto scene = make_reflectance_scene(material, hemisphere_lights(100, 7));
    BiPolynomialOptions options;
    options.threads = 2;
    const FalloffEstimate estimate = estimate_incidence_falloff(scene.observations, options);
    EXPECT_EQ(estimate.pixels, scene.observations.pixel_count()) << material;
    EXPECT_LT(std::abs(estimate.kappa), 0.02) << material;
    BiPolynomialOptions published = options;
    published.falloff = 0.0;
    const double with = mean_error(solve_bipolynomial(scene.observations, options), scene);
    const double without = mean_error(solve_bipolynomial(scene.observations, published), scene);
    EXPECT_LT(with, without + 0.02) << material;
  }
}

TEST(IncidenceFalloff, DielectricUnderConeLightsBeatsTheLambertianStart) {
  // Wolff's diffuse at η = 1.5 is 0.95 of Lambert's at 60° incidence, 0.64 at 80°.
  const auto scene =
      make_reflectance_scene("dielectric:eta=1.5,ks=0", hemisphere_lights(96, 5, kConeZ), 16, 10);
  BiPolynomialOptions options;
  options.threads = 2;
  const FalloffEstimate estimate = estimate_incidence_falloff(scene.observations, options);
  EXPECT_GT(estimate.kappa, 0.1);
  EXPECT_LT(estimate.kappa, 1.5);
  EXPECT_LE(estimate.quartile_low, estimate.kappa);
  EXPECT_GE(estimate.quartile_high, estimate.kappa);
  const SolveResult with = solve_bipolynomial(scene.observations, options);
  EXPECT_TRUE(with.parameters["falloff"]["estimated"].get<bool>());
  EXPECT_NEAR(with.parameters["falloff"]["kappa"].get<double>(), estimate.kappa, 1e-12);
  BiPolynomialOptions published = options;
  published.falloff = 0.0;
  const SolveResult without = solve_bipolynomial(scene.observations, published);
  EXPECT_FALSE(without.parameters["falloff"]["estimated"].get<bool>());
  const double e_with = mean_error(with, scene), e_without = mean_error(without, scene);
  // Measured: 1.17° against 1.70°.
  EXPECT_LT(e_with, 0.8 * e_without) << "with fall-off " << e_with << ", Lambertian start " << e_without;
  // auto takes the same start.
  AutoOptions automatic;
  automatic.threads = 2;
  AutoOptions automatic_published = automatic;
  automatic_published.bipolynomial.falloff = 0.0;
  EXPECT_LT(mean_error(solve_auto(scene.observations, automatic), scene),
            mean_error(solve_auto(scene.observations, automatic_published), scene));
}

// Noise makes T_low's ranking keep the observations near its cut only when
// their noise is negative, which reads as a negative κ (clamped at −0.5).
// Fitting it must not cost accuracy, over the hemisphere or in a cone.
// Measured (fall-off against Lambertian start): hemisphere λ 0.05 0.42 / 0.43,
// λ 0.15 1.20 / 1.38; 43° cone λ 0.05 1.59 / 1.65, λ 0.15 5.06 / 6.91.
TEST(IncidenceFalloff, NoisyLambertianSurfacesAreNotHurt) {
  for (const double min_z : {0.1, kConeZ}) {
    for (const double noise : {0.05, 0.15}) {
      const auto scene = make_reflectance_scene("lambert", hemisphere_lights(100, 7, min_z), 36, 45, noise);
      BiPolynomialOptions options;
      options.threads = 2;
      const SolveResult with = solve_bipolynomial(scene.observations, options);
      EXPECT_LT(with.parameters["falloff"]["kappa"].get<double>(), 0.0) << min_z << " " << noise;
      BiPolynomialOptions published = options;
      published.falloff = 0.0;
      EXPECT_LT(mean_error(with, scene), mean_error(solve_bipolynomial(scene.observations, published), scene))
          << "lights above z " << min_z << ", noise " << noise;
    }
  }
}

TEST(IncidenceFalloff, EstimateDoesNotDependOnThreadsAndSamplesLargeMasks) {
  const auto scene =
      make_reflectance_scene("dielectric:eta=1.4,ks=0.2", hemisphere_lights(60, 3, kConeZ), 20, 12);
  BiPolynomialOptions one, two;
  one.threads = 1;
  two.threads = 2;
  const auto a = estimate_incidence_falloff(scene.observations, one);
  const auto b = estimate_incidence_falloff(scene.observations, two);
  EXPECT_EQ(a.kappa, b.kappa);
  EXPECT_EQ(a.pixels, b.pixels);
  EXPECT_GE(a.pixels, 235u);  // of 240: a fit that degenerates or does not converge does not vote
  EXPECT_LE(a.pixels, 240u);
  // At most 100 of the 240 pixels, spread evenly: every 3rd.
  const auto sampled = estimate_incidence_falloff(scene.observations, one, 100);
  EXPECT_GE(sampled.pixels, 78u);
  EXPECT_LE(sampled.pixels, 80u);
  EXPECT_NEAR(sampled.kappa, a.kappa, 0.2);
  // 0 means every pixel.
  EXPECT_EQ(estimate_incidence_falloff(scene.observations, one, 0).pixels, a.pixels);
  // 40 voting pixels are too few: κ stays 0.
  const auto few = estimate_incidence_falloff(scene.observations, one, 40);
  EXPECT_LE(few.pixels, 40u);
  EXPECT_EQ(few.kappa, 0.0);
}

// 12 lights (a UW-style set) leave the bilinear fit 6 observations: too few
// to tell t from t², so no pixel votes and every start is Lambert's.
TEST(IncidenceFalloff, SparseLightsKeepTheLambertianStart) {
  const auto scene = make_reflectance_scene("dielectric:eta=1.5,ks=0.2", hemisphere_lights(12, 9, 0.3));
  BiPolynomialOptions options;
  options.order = 1;
  const FalloffEstimate estimate = estimate_incidence_falloff(scene.observations, options);
  EXPECT_EQ(estimate.pixels, 0u);
  EXPECT_EQ(estimate.kappa, 0.0);
  BiPolynomialOptions forced = options;
  forced.falloff = -0.5;  // even a given κ is not applied to such pixels
  BiPolynomialOptions published = options;
  published.falloff = 0.0;
  const SolveResult a = solve_bipolynomial(scene.observations, forced);
  const SolveResult b = solve_bipolynomial(scene.observations, published);
  ASSERT_GT(b.summary.pixels_solved, 0u);
  EXPECT_EQ(cv::norm(a.normals, b.normals, cv::NORM_INF), 0.0);
}

TEST(IncidenceFalloff, BadValuesAreNamed) {
  BiPolynomialOptions options;
  options.falloff = 7.0;
  EXPECT_NE(error_of([&] { options.check(); }).find("--falloff"), std::string::npos);
  options.falloff = std::nan("");
  EXPECT_NE(error_of([&] { options.check(); }).find("--falloff"), std::string::npos);
  options.falloff = -0.5;
  EXPECT_EQ(error_of([&] { options.check(); }), "(no InputError)");
}

}  // namespace
}  // namespace lightstage
