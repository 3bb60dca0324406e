// Reflectometry and relighting: the bi-polynomial model, object-level fits
// with known normals, and rendering from per-pixel coefficients.
#include "lightstage/host/eval/angular_error.hpp"
#include "lightstage/host/io/solve_output.hpp"
#include "lightstage/host/reflectance/bipolynomial_model.hpp"
#include "lightstage/host/reflectance/reflectometry.hpp"
#include "lightstage/host/reflectance/relight.hpp"
#include "lightstage/host/solvers/bipolynomial.hpp"
#include "lightstage/testing/errors.hpp"
#include "lightstage/testing/paths.hpp"
#include "reflectance_scene.hpp"

#include <gtest/gtest.h>

namespace lightstage {
namespace {

using testing::hemisphere_lights;
using testing::make_reflectance_scene;

TEST(BiPolynomialModel, BasisAndEvaluationAgree) {
  for (int order = 1; order <= 3; ++order) {
    const int terms = bipolynomial_term_count(order);
    Eigen::VectorXd c = Eigen::VectorXd::LinSpaced(terms, 0.3, -0.7);
    Eigen::VectorXd basis(terms);
    bipolynomial_basis(order, 0.8, 0.6, basis.data());
    EXPECT_NEAR(basis.dot(c), evaluate_bipolynomial(order, c, 0.8, 0.6), 1e-12);
    EXPECT_EQ(static_cast<int>(bipolynomial_term_names(order).size()), terms);
  }
  EXPECT_EQ(bipolynomial_term_names(2)[1], "C01");
  EXPECT_NE(testing::error_of([] { bipolynomial_term_count(4); }).find("order"), std::string::npos);
}

TEST(BiPolynomialModel, RankOneCoefficientsFactoriseExactly) {
  const Eigen::Vector3d a(0.5, 0.2, 0.1), b(1.0, -0.3, 0.05);
  Eigen::VectorXd c(9);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) c(i * 3 + j) = a(i) * b(j);
  const auto f = factorise_bipolynomial(2, c);
  EXPECT_LT(f.relative_error, 1e-12);
  for (double x : {0.2, 0.7, 1.0}) {
    for (double y : {0.5, 0.9}) {
      const double rho1 = f.a(0) + f.a(1) * x + f.a(2) * x * x;
      const double rho2 = f.b(0) + f.b(1) * y + f.b(2) * y * y;
      EXPECT_NEAR(rho1 * rho2, evaluate_bipolynomial(2, c, x, y), 1e-12);
    }
  }
}

TEST(Reflectometry, ModelsRankAsTheDissertationFindsOnABroadLobe) {
  const auto scene =
      make_reflectance_scene("cook-torrance:roughness=0.5,ks=0.5", hemisphere_lights(60, 21), 16, 10);
  const ReflectanceSamples samples = collect_samples(scene.observations, scene.truth);
  EXPECT_GT(samples.size(), 1000u);
  const auto lambert = fit_lambert(samples);
  const auto bilinear = fit_bipolynomial_model(samples, 1);
  const auto biquadratic = fit_bipolynomial_model(samples, 2);
  const auto bicubic = fit_bipolynomial_model(samples, 3);
  const auto cook = fit_cook_torrance(samples);
  EXPECT_LT(biquadratic.rmse, lambert.rmse);
  EXPECT_LE(bicubic.rmse, biquadratic.rmse + 1e-12);
  EXPECT_LE(biquadratic.rmse, bilinear.rmse + 1e-12);
  // The generating model is Cook–Torrance itself: its fit is near exact and finds the roughness.
  EXPECT_LT(cook.relative_rmse, 0.05);
  EXPECT_NEAR(cook.parameters(2), 0.5, 0.1);
}

TEST(Reflectometry, LambertFitRecoversTheAlbedo) {
  const auto scene = make_reflectance_scene("lambert", hemisphere_lights(30, 22));
  const auto fit = fit_lambert(collect_samples(scene.observations, scene.truth));
  EXPECT_NEAR(fit.parameters(0), 0.5, 1e-4);
  EXPECT_LT(fit.rmse, 1e-5);
}

TEST(Relight, SolvedFolderRelightsCloseToTheTruth) {
  // A broad, low-frequency material: the bi-polynomial BRDF must predict new lights well.
  const char* material = "cook-torrance:roughness=0.8,ks=0.3";
  const auto scene = make_reflectance_scene(material, hemisphere_lights(100, 23), 16, 10);
  BiPolynomialOptions options;
  options.t_low = 0.5;
  const SolveResult result = solve_bipolynomial(scene.observations, options);
  const auto dir = testing::scratch_dir() / "result";
  io::write_solve_outputs(dir, result, "synthetic");
  const RelightModel model = load_relight_model(dir);
  ASSERT_EQ(model.order, 2);
  ASSERT_EQ(model.coefficients.channels(), 9);
  const sim::Material truth = sim::parse_material(material);
  for (const Vec3& l : turntable_lights(4, 50)) {
    const cv::Mat image = relight(model, l);
    double error = 0, total = 0;
    for (std::size_t p = 0; p < scene.observations.pixel_count(); ++p) {
      const cv::Point at = scene.observations.pixels[p];
      const cv::Vec3f t = scene.truth.at<cv::Vec3f>(at);
      const double expected = 0.5 * truth.shading(0, 0, Vec3(t[0], t[1], t[2]), l, Vec3::UnitZ());
      error += std::abs(image.at<float>(at) - expected);
      total += expected;
    }
    EXPECT_LT(error / total, 0.1) << l.transpose();
  }
}

TEST(Relight, LambertianFallbackAndBadInput) {
  RelightModel model;
  model.normals = cv::Mat(1, 1, CV_32FC3, cv::Scalar(0, 0, 1));
  model.solved = cv::Mat(1, 1, CV_8UC1, cv::Scalar(255));
  model.albedo = cv::Mat(1, 1, CV_32FC1, cv::Scalar(0.4));
  const cv::Mat image = relight(model, Vec3(0, 0.6, 0.8));
  EXPECT_NEAR(image.at<float>(0, 0), 0.4 * 0.8, 1e-6);
  EXPECT_NE(testing::error_of([&] { relight(model, Vec3::Zero()); }).find("--light"), std::string::npos);
  EXPECT_NE(testing::error_of([] { turntable_lights(0, 30); }).find("--turntable"), std::string::npos);
  EXPECT_NE(testing::error_of([] { load_relight_model("/nonexistent/folder"); }).find("/nonexistent/folder"),
            std::string::npos);
}

// Colour: the polynomial part takes the chroma, the specular lobe stays white,
// and the grey of the colour image is the grey relighting.
TEST(Relight, ColourTakesTheChromaOnThePolynomialAndKeepsTheLobeWhite) {
  RelightModel model;
  model.normals = cv::Mat(1, 2, CV_32FC3, cv::Scalar(0, 0, 1));
  model.solved = cv::Mat(1, 2, CV_8UC1, cv::Scalar(255));
  model.albedo = cv::Mat(1, 2, CV_32FC1, cv::Scalar(0.4));
  model.order = 1;
  model.lobe_width = 0.2;
  model.coefficients = cv::Mat(1, 2, CV_32FC(5), cv::Scalar::all(0));
  // Pixel 0: ρ = 0.3 + lobe · 0.5; pixel 1: no lobe.
  model.coefficients.ptr<float>(0)[0] = 0.3f;
  model.coefficients.ptr<float>(0)[4] = 0.5f;
  model.coefficients.ptr<float>(0)[5] = 0.3f;
  const cv::Vec3f chroma(0.6f, 0.9f, 1.3f);  // B G R
  model.chroma = cv::Mat(1, 2, CV_32FC3, cv::Scalar(chroma[0], chroma[1], chroma[2]));
  const Vec3 light(0, 0.6, 0.8);
  const cv::Mat grey = relight(model, light);
  const cv::Mat colour = relight_colour(model, light);
  ASSERT_EQ(colour.type(), CV_32FC3);
  const Vec3 h = (light.normalized() + Vec3::UnitZ()).normalized();
  const double lobe = 0.5 * specular_lobe(h.z(), 0.2), nl = 0.8;
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(colour.at<cv::Vec3f>(0, 0)[c], (chroma[c] * 0.3 + lobe) * nl, 1e-6) << c;
    EXPECT_NEAR(colour.at<cv::Vec3f>(0, 1)[c], chroma[c] * 0.3 * nl, 1e-6) << c;
  }
  // BT.601 grey of the colour = the grey image (chroma's grey is not 1 here: weigh it in).
  const double chroma_grey = 0.2989 * chroma[2] + 0.5870 * chroma[1] + 0.1140 * chroma[0];
  const cv::Vec3f c0 = colour.at<cv::Vec3f>(0, 1);
  EXPECT_NEAR((0.2989 * c0[2] + 0.5870 * c0[1] + 0.1140 * c0[0]) / chroma_grey, grey.at<float>(0, 1), 1e-6);
  // Without chroma, the grey in every channel.
  model.chroma.release();
  const cv::Mat neutral = relight_colour(model, light);
  for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(neutral.at<cv::Vec3f>(0, 0)[c], grey.at<float>(0, 0));
}

}  // namespace
}  // namespace lightstage
