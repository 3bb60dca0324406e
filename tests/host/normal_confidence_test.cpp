// The confidence's predicted error (solvers/normal_confidence.hpp) on
// synthetic Lambertian pixels: calibrated to the error noise gives, growing
// with it, large where the answer kept an outlier, and infinite where the
// data leave the normal open.
#include "lightstage/host/solvers/normal_confidence.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/geometry.hpp"
#include "lightstage/host/solvers/lambertian.hpp"
#include "synthetic.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <random>
#include <string>
#include <vector>

namespace lightstage {
namespace {

using testing::make_scene;
using testing::SyntheticScene;

// Gaussian noise of `sigma` on every lit observation.
void add_noise(Observations& observations, double sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, sigma);
  for (Eigen::Index p = 0; p < observations.intensities.rows(); ++p)
    for (Eigen::Index j = 0; j < observations.intensities.cols(); ++j)
      if (observations.intensities(p, j) > 0)
        observations.intensities(p, j) += static_cast<float>(noise(rng));
}

SolveResult solve_l2(const Observations& observations) {
  L2Options options;
  options.shadow_threshold = 0;
  options.threads = 2;
  return solve_lambertian(observations, options);
}

struct Errors {           // degrees, over the solved pixels
  double rms_actual = 0;  // of the solved normals against the truth
  double rms_predicted = 0;
};

Errors errors(const SyntheticScene& scene, const SolveResult& result, const cv::Mat& predicted) {
  double actual = 0, expected = 0;
  int count = 0;
  for (std::size_t p = 0; p < scene.normals.size(); ++p) {
    const cv::Point at = scene.observations.pixels[p];
    if (result.solved.at<std::uint8_t>(at) == 0) continue;
    const cv::Vec3f n = result.normals.at<cv::Vec3f>(at);
    actual += std::pow(angle_between_deg(Vec3(n[0], n[1], n[2]), scene.normals[p]), 2);
    expected += std::pow(predicted.at<float>(at), 2);
    ++count;
  }
  return {std::sqrt(actual / count), std::sqrt(expected / count)};
}

// A solve result holding the true normals and albedos.
SolveResult truth_as_answer(const SyntheticScene& scene) {
  SolveResult result;
  const cv::Size size = scene.observations.size;
  result.normals = cv::Mat(size, CV_32FC3, cv::Scalar::all(0));
  result.albedo = cv::Mat(size, CV_32FC1, cv::Scalar::all(0));
  result.solved = cv::Mat(size, CV_8UC1, cv::Scalar::all(255));
  for (std::size_t p = 0; p < scene.normals.size(); ++p) {
    const cv::Point at = scene.observations.pixels[p];
    const Vec3& n = scene.normals[p];
    result.normals.at<cv::Vec3f>(at) =
        cv::Vec3f(static_cast<float>(n.x()), static_cast<float>(n.y()), static_cast<float>(n.z()));
    result.albedo.at<float>(at) = static_cast<float>(scene.albedo[p]);
  }
  return result;
}

TEST(NormalConfidence, PredictsTheErrorNoiseGivesAndGrowsWithIt) {
  ConfidenceOptions options;
  options.threads = 2;
  std::vector<Errors> measured;
  for (const double sigma : {0.005, 0.02}) {
    SyntheticScene scene = make_scene(24, 24, 40, 5, /*clamp_shadows=*/true);
    add_noise(scene.observations, sigma, 9);
    const SolveResult result = solve_l2(scene.observations);
    measured.push_back(errors(scene, result, predict_normal_error(scene.observations, result, options)));
    std::printf("sigma %.3f: rms actual %.3f deg, rms predicted %.3f deg\n", sigma,
                measured.back().rms_actual, measured.back().rms_predicted);
    // The right size: the error the noise gives, within a quarter.
    EXPECT_GT(measured.back().rms_predicted, 0.75 * measured.back().rms_actual);
    EXPECT_LT(measured.back().rms_predicted, 1.25 * measured.back().rms_actual);
  }
  // Four times the noise, about four times the predicted error.
  const double ratio = measured[1].rms_predicted / measured[0].rms_predicted;
  EXPECT_GT(ratio, 3.0);
  EXPECT_LT(ratio, 5.0);
}

TEST(NormalConfidence, ExactDataIsConfidentUpToTheQuantisationFloor) {
  const SyntheticScene scene = make_scene(8, 8, 20, 3, /*clamp_shadows=*/true);
  const SolveResult result = solve_l2(scene.observations);
  ConfidenceOptions options;
  const cv::Mat predicted = predict_normal_error(scene.observations, result, options);
  double worst = 0;
  for (const cv::Point& at : scene.observations.pixels)
    if (result.solved.at<std::uint8_t>(at) != 0)
      worst = std::max(worst, static_cast<double>(predicted.at<float>(at)));
  EXPECT_GT(worst, 0.0);  // the floor: 1e-3 of the mean lit value
  EXPECT_LT(worst, 1.0);
  options.min_relative_sigma = 0;
  const cv::Mat unfloored = predict_normal_error(scene.observations, result, options);
  for (const cv::Point& at : scene.observations.pixels) {
    if (result.solved.at<std::uint8_t>(at) != 0) {
      EXPECT_LT(unfloored.at<float>(at), 1e-3);
    }
  }
}

TEST(NormalConfidence, AnOutlierTheAnswerKeptLowersTheConfidence) {
  SyntheticScene scene = make_scene(1, 1, 30, 7, /*clamp_shadows=*/true);
  add_noise(scene.observations, 0.002, 1);
  ConfidenceOptions options;
  const SolveResult clean = solve_l2(scene.observations);
  const double clean_error = predict_normal_error(scene.observations, clean, options).at<float>(0, 0);
  // A highlight on the brightest lit light: least squares keeps it and tilts.
  Eigen::Index brightest = 0;
  scene.observations.intensities.row(0).maxCoeff(&brightest);
  scene.observations.intensities(0, brightest) *= 4;
  const SolveResult tilted = solve_l2(scene.observations);
  const cv::Vec3f n = tilted.normals.at<cv::Vec3f>(0, 0);
  const double actual = angle_between_deg(Vec3(n[0], n[1], n[2]), scene.normals[0]);
  const double predicted = predict_normal_error(scene.observations, tilted, options).at<float>(0, 0);
  std::printf("outlier: actual %.2f deg, predicted %.2f deg (clean %.3f deg)\n", actual, predicted,
              clean_error);
  EXPECT_GT(actual, 1.0);
  EXPECT_GT(predicted, 0.5 * actual);
  EXPECT_GT(predicted, 10 * clean_error);
}

// Shadows and highlights the answer rightly ignored are not held against it.
TEST(NormalConfidence, OutliersTheAnswerIgnoredLeaveItConfident) {
  SyntheticScene scene = make_scene(6, 6, 40, 4, /*clamp_shadows=*/true);
  add_noise(scene.observations, 0.002, 3);
  const SolveResult truth = truth_as_answer(scene);
  const ConfidenceOptions options;
  const cv::Mat clean = predict_normal_error(scene.observations, truth, options);
  // Every pixel's three brightest lights as highlights, two more in a cast shadow (lit, but dark).
  Observations& observations = scene.observations;
  for (Eigen::Index p = 0; p < observations.intensities.rows(); ++p) {
    std::vector<Eigen::Index> order(static_cast<std::size_t>(observations.intensities.cols()));
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index b) {
      return observations.intensities(p, a) > observations.intensities(p, b);
    });
    for (int k = 0; k < 3; ++k) observations.intensities(p, order[static_cast<std::size_t>(k)]) *= 3;
    for (int k = 3; k < 5; ++k) observations.intensities(p, order[static_cast<std::size_t>(k)]) *= 0.2f;
  }
  const cv::Mat outliers = predict_normal_error(observations, truth, options);
  for (const cv::Point& at : observations.pixels) {
    EXPECT_LT(outliers.at<float>(at), 2 * clean.at<float>(at) + 0.05) << at;
  }
}

// Three lit lights fix the normal with nothing to spare: finite, not trimmed to two.
TEST(NormalConfidence, ThreeLitLightsGiveAFiniteError) {
  SyntheticScene scene = make_scene(16, 16, 3, 6, /*clamp_shadows=*/false);
  add_noise(scene.observations, 0.01, 2);
  const cv::Mat predicted =
      predict_normal_error(scene.observations, truth_as_answer(scene), ConfidenceOptions{});
  int finite = 0, lit_three = 0;
  for (std::size_t p = 0; p < scene.normals.size(); ++p) {
    const cv::Point at = scene.observations.pixels[p];
    if ((scene.observations.intensities.row(static_cast<Eigen::Index>(p)).array() > 0).count() < 3) continue;
    ++lit_three;
    finite += std::isfinite(predicted.at<float>(at)) ? 1 : 0;
  }
  EXPECT_GT(lit_three, 0);
  EXPECT_EQ(finite, lit_three);
}

TEST(NormalConfidence, LeavesANormalTheDataDoNotFixInfinite) {
  SyntheticScene scene = make_scene(2, 1, 12, 2, /*clamp_shadows=*/true);
  const SolveResult result = solve_l2(scene.observations);
  // Two lit lights remain at the first pixel: its normal is open.
  for (Eigen::Index j = 2; j < scene.observations.intensities.cols(); ++j)
    scene.observations.intensities(0, j) = 0;
  const cv::Mat predicted = predict_normal_error(scene.observations, result, ConfidenceOptions{});
  EXPECT_TRUE(std::isinf(predicted.at<float>(0, 0)));
  EXPECT_TRUE(std::isfinite(predicted.at<float>(0, 1)));
  const cv::Mat confidence = confidence_from_error(predicted, result.solved, 1.0);
  EXPECT_EQ(confidence.at<float>(0, 0), 0.0f);
  EXPECT_GT(confidence.at<float>(0, 1), 0.0f);
}

// The solve's clamp of a normal facing away, as solve_with applies it before the separate pass.
SolveResult facing_the_camera(SolveResult result) {
  result.normals.forEach<cv::Vec3f>([](cv::Vec3f& n, const int*) {
    if (n[2] < 0) n = on_horizon(n);
  });
  return result;
}

// l2 solving one pixel at a time predicts each error while it has the pixel's
// lights: the same floats as the separate pass over the solved (and clamped)
// answer, with near lights, a threshold or T_low, saturated observations, a
// pixel never lit and a normal facing away.
TEST(NormalConfidence, L2PredictsAsItSolvesWhatTheSeparatePassPredicts) {
  struct Case {
    const char* name;
    bool near;
    double shadow_threshold, t_low;
  };
  for (const Case& c : {Case{"near lights", true, -1, 1}, Case{"a threshold", false, 0.02, 1},
                        Case{"T_low", false, -1, 0.75}}) {
    SCOPED_TRACE(c.name);
    SyntheticScene scene = make_scene(12, 10, 24, 8, /*clamp_shadows=*/true);
    Observations& observations = scene.observations;
    add_noise(observations, 0.01, 9);
    for (Eigen::Index p = 0; p < observations.intensities.rows(); p += 7)
      observations.saturated(p, p % 24) = true;
    if (c.near) {
      NearLights lights;
      lights.led_positions_mm = 400.0 * observations.lights;
      lights.points_mm = Eigen::MatrixX3d::Zero(observations.intensities.rows(), 3);
      for (std::size_t p = 0; p < observations.pixels.size(); ++p)
        lights.points_mm.row(static_cast<Eigen::Index>(p)) << observations.pixels[p].x,
            observations.pixels[p].y, 0;
      observations.near = lights;
    }
    // Pixel 0 is exactly Lambertian for a normal below the horizon, negative values and all; pixel 1 is dark.
    const Vec3 away = Vec3(0.8, 0.3, -0.5).normalized();
    for (Eigen::Index j = 0; j < observations.intensities.cols(); ++j) {
      observations.intensities(0, j) = static_cast<float>(0.6 * observations.lights.row(j).dot(away));
      observations.intensities(1, j) = 0;
    }
    ConfidenceOptions confidence;
    confidence.shadow_threshold = 0.02;
    L2Options options;
    options.shadow_threshold = c.shadow_threshold;
    options.t_low = c.t_low;
    options.threads = 2;
    options.confidence = confidence;
    const SolveResult predicting = solve_lambertian(observations, options);
    ASSERT_FALSE(predicting.predicted_error.empty());
    EXPECT_LT(predicting.normals.at<cv::Vec3f>(observations.pixels[0])[2], 0.0f);
    EXPECT_EQ(predicting.solved.at<std::uint8_t>(observations.pixels[1]), 0);
    const cv::Mat separate = predict_normal_error(observations, facing_the_camera(predicting), confidence);
    int finite = 0;
    for (const cv::Point& at : observations.pixels) {
      const float fused = predicting.predicted_error.at<float>(at), alone = separate.at<float>(at);
      EXPECT_TRUE(fused == alone || (std::isinf(fused) && std::isinf(alone)))
          << at << ": " << fused << " vs " << alone;
      finite += std::isfinite(alone) && alone > 0 ? 1 : 0;
    }
    EXPECT_GT(finite, 100);
    options.confidence.reset();
    EXPECT_TRUE(solve_lambertian(observations, options).predicted_error.empty());
  }
  // Every pixel sharing one pseudo-inverse predicts nothing: the separate pass judges them.
  SyntheticScene scene = make_scene(4, 4, 12, 3, /*clamp_shadows=*/false);
  L2Options all;
  all.confidence = ConfidenceOptions{};
  EXPECT_TRUE(solve_lambertian(scene.observations, all).predicted_error.empty());
  // The confidence reads the saturation flags: flags of another size are an input error, not a bad read.
  scene.observations.saturated = FlagMatrix::Constant(3, 12, false);
  all.shadow_threshold = 0;
  EXPECT_THROW(solve_lambertian(scene.observations, all), InputError);
}

TEST(NormalConfidence, RefusesOptionsOutOfRangeNamingTheField) {
  ConfidenceOptions options;
  options.trim = 0.5;
  try {
    options.check();
    FAIL() << "trim 0.5 accepted";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("ConfidenceOptions.trim"), std::string::npos);
  }
  options = ConfidenceOptions{};
  options.scale_deg = 0;
  EXPECT_THROW(options.check(), InputError);
}

}  // namespace
}  // namespace lightstage
