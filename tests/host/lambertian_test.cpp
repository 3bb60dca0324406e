#include "lightstage/host/solvers/lambertian.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/geometry.hpp"
#include "synthetic.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

namespace lightstage {
namespace {

using testing::make_scene;
using testing::SyntheticScene;

Vec3 normal_at(const SolveResult& result, const cv::Point& pixel) {
  const auto n = result.normals.at<cv::Vec3f>(pixel);
  return {n[0], n[1], n[2]};
}

// Largest angle (degrees) between solved and true normals; counts solved pixels.
double max_error_deg(const SyntheticScene& scene, const SolveResult& result, std::size_t* solved = nullptr) {
  double worst = 0;
  std::size_t count = 0;
  for (std::size_t p = 0; p < scene.normals.size(); ++p) {
    const cv::Point pixel = scene.observations.pixels[p];
    if (result.solved.at<std::uint8_t>(pixel) == 0) continue;
    ++count;
    worst = std::max(worst, angle_between_deg(normal_at(result, pixel), scene.normals[p]));
  }
  if (solved) *solved = count;
  return worst;
}

// "Exact": the normal maps are float, so a perfect solve is the true unit
// normal rounded to float — within float epsilon per component, which is up
// to ~3e-6 degrees of angle. (A solve in float, or from rounded shading, is
// off by 1e-5 degrees and more.)
constexpr double kExactDeg = 1e-5;

bool exact_to_float(const SyntheticScene& scene, const SolveResult& result) {
  for (std::size_t p = 0; p < scene.normals.size(); ++p) {
    const cv::Point pixel = scene.observations.pixels[p];
    if (result.solved.at<std::uint8_t>(pixel) == 0) continue;
    const Vec3 error = normal_at(result, pixel) - scene.normals[p];
    if (error.cwiseAbs().maxCoeff() > std::numeric_limits<float>::epsilon()) return false;
  }
  return true;
}

bool identical(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && a.isContinuous() && b.isContinuous() &&
         std::memcmp(a.data, b.data, a.total() * a.elemSize()) == 0;
}

TEST(HostLambertian, ExactShadingGivesExactNormalsAndAlbedo) {
  const auto scene = make_scene(40, 30, 12, 1, /*clamp_shadows=*/false);
  const auto result = solve_lambertian(scene.observations, L2Options{});
  EXPECT_EQ(result.summary.method, "l2");
  EXPECT_EQ(result.summary.pixels_in_mask, 1200u);
  EXPECT_EQ(result.summary.pixels_solved, 1200u);
  std::size_t solved = 0;
  EXPECT_LT(max_error_deg(scene, result, &solved), kExactDeg);
  EXPECT_TRUE(exact_to_float(scene, result));
  EXPECT_EQ(solved, 1200u);
  for (std::size_t p = 0; p < scene.albedo.size(); ++p) {
    const cv::Point pixel = scene.observations.pixels[p];
    ASSERT_NEAR(result.albedo.at<float>(pixel), scene.albedo[p], 1e-6);
    ASSERT_LT(result.residual.at<float>(pixel), 1e-6);
  }
}

TEST(HostLambertian, ShadowThresholdDropsClampedShadowsExactly) {
  // Lights down to 0.3 elevation and normals down to 0.05: many observations are shadowed.
  const auto scene = make_scene(40, 30, 20, 2, /*clamp_shadows=*/true);
  std::size_t shadowed = 0;
  for (Eigen::Index p = 0; p < scene.observations.intensities.rows(); ++p) {
    for (Eigen::Index j = 0; j < scene.observations.intensities.cols(); ++j) {
      shadowed += scene.observations.intensities(p, j) == 0.0f ? 1 : 0;
    }
  }
  ASSERT_GT(shadowed, 500u) << "the scene should have shadows to drop";

  // Without the threshold the shadows bias the fit...
  const auto biased = solve_lambertian(scene.observations, L2Options{});
  EXPECT_GT(max_error_deg(scene, biased), 1.0);
  // ... with it, every pixel with enough lit observations is exact.
  L2Options options;
  options.shadow_threshold = 0;
  const auto result = solve_lambertian(scene.observations, options);
  std::size_t solved = 0;
  EXPECT_LT(max_error_deg(scene, result, &solved), kExactDeg);
  EXPECT_TRUE(exact_to_float(scene, result));
  EXPECT_EQ(solved, result.summary.pixels_solved);
  EXPECT_EQ(result.summary.pixels_solved + result.summary.pixels_rejected_too_few_observations +
                result.summary.pixels_rejected_degenerate,
            1200u);
  EXPECT_GT(result.summary.pixels_solved, 1100u);
}

TEST(HostLambertian, TLowKeepsTheDarkestObservations) {
  auto scene = make_scene(20, 20, 20, 3, /*clamp_shadows=*/false);
  auto& values = scene.observations.intensities;
  // Specular-like spikes on the 5 brightest of 20 observations of every pixel.
  for (Eigen::Index p = 0; p < values.rows(); ++p) {
    std::vector<Eigen::Index> order(static_cast<std::size_t>(values.cols()));
    for (Eigen::Index j = 0; j < values.cols(); ++j) order[static_cast<std::size_t>(j)] = j;
    std::sort(order.begin(), order.end(), [&](auto a, auto b) { return values(p, a) > values(p, b); });
    for (int k = 0; k < 5; ++k) values(p, order[static_cast<std::size_t>(k)]) += 2.0f;
  }
  EXPECT_GT(max_error_deg(scene, solve_lambertian(scene.observations, L2Options{})), 1.0);

  L2Options low;
  low.t_low = 0.75;  // keeps exactly 15 of 20: the spikes go
  std::size_t solved = 0;
  const auto result = solve_lambertian(scene.observations, low);
  EXPECT_LT(max_error_deg(scene, result, &solved), kExactDeg);
  EXPECT_TRUE(exact_to_float(scene, result));
  EXPECT_EQ(solved, 400u);

  low.t_low = 0.8;  // keeps 16: one spike stays in
  EXPECT_GT(max_error_deg(scene, solve_lambertian(scene.observations, low)), 0.01);
}

TEST(HostLambertian, RejectsPixelsWithTooFewObservations) {
  const auto scene = make_scene(10, 10, 20, 4, false);
  L2Options options;
  options.t_low = 0.1;  // 2 of 20 observations
  const auto result = solve_lambertian(scene.observations, options);
  EXPECT_EQ(result.summary.pixels_solved, 0u);
  EXPECT_EQ(result.summary.pixels_rejected_too_few_observations, 100u);
  EXPECT_EQ(cv::countNonZero(result.solved), 0);
  EXPECT_EQ(cv::countNonZero(result.albedo), 0);

  options.t_low = 1;
  options.min_observations = 21;  // more than there are images (fast path)
  const auto all = solve_lambertian(scene.observations, options);
  EXPECT_EQ(all.summary.pixels_rejected_too_few_observations, 100u);
  EXPECT_EQ(all.summary.pixels_solved, 0u);
}

TEST(HostLambertian, RejectsCoplanarLightsOnBothPaths) {
  auto scene = make_scene(8, 8, 10, 5, false);
  // All lights in the x-z plane: y of the normal is unobservable.
  for (Eigen::Index j = 0; j < scene.observations.lights.rows(); ++j) {
    const double a = 0.3 + 0.2 * static_cast<double>(j);
    scene.observations.lights.row(j) << std::cos(a), 0.0, std::sin(a);
  }
  const auto fast = solve_lambertian(scene.observations, L2Options{});
  EXPECT_EQ(fast.summary.pixels_rejected_degenerate, 64u);
  EXPECT_EQ(fast.summary.pixels_solved, 0u);
  L2Options select;
  select.shadow_threshold = -1;
  select.t_low = 0.99;
  const auto selected = solve_lambertian(scene.observations, select);
  EXPECT_EQ(selected.summary.pixels_rejected_degenerate, 64u);
  EXPECT_EQ(cv::countNonZero(selected.solved), 0);
}

// Lights are summed two at a time: with an odd count, the last one alone
// makes the normal observable here (the others lie in the x-z plane), in the
// per-pixel solve and in the confidence it predicts as it goes.
TEST(HostLambertian, TheLastOfAnOddCountOfLightsIsSummedToo) {
  auto scene = make_scene(8, 8, 11, 5, false);
  Observations& obs = scene.observations;
  for (Eigen::Index j = 0; j + 1 < obs.lights.rows(); ++j) {
    const double a = 0.3 + 0.2 * static_cast<double>(j);
    obs.lights.row(j) << std::cos(a), 0.0, std::sin(a);
  }
  obs.lights.row(10) << 0.2, 0.5, 0.84;
  for (std::size_t p = 0; p < scene.normals.size(); ++p) {  // facing every light
    scene.normals[p] =
        Vec3(0.05 * static_cast<double>(p % 3), 0.05 * static_cast<double>(p % 5), 1.0).normalized();
  }
  for (std::size_t p = 0; p < scene.normals.size(); ++p)
    for (Eigen::Index j = 0; j < obs.lights.rows(); ++j)
      obs.intensities(static_cast<Eigen::Index>(p), j) =
          static_cast<float>(scene.albedo[p] * obs.lights.row(j).dot(scene.normals[p].transpose()));
  L2Options select;
  select.shadow_threshold = -1;
  select.t_low = 0.99;  // all 11 kept, by the per-pixel selection
  select.confidence = ConfidenceOptions{};
  const auto result = solve_lambertian(obs, select);
  std::size_t solved = 0;
  EXPECT_LT(max_error_deg(scene, result, &solved), 1e-3);
  EXPECT_EQ(solved, 64u);
  ASSERT_FALSE(result.predicted_error.empty());
  for (const cv::Point& at : obs.pixels)
    EXPECT_TRUE(std::isfinite(result.predicted_error.at<float>(at))) << at;
}

TEST(HostLambertian, AllDarkPixelIsRejectedNotGuessed) {
  auto scene = make_scene(4, 4, 8, 6, false);
  scene.observations.intensities.row(5).setZero();
  const auto result = solve_lambertian(scene.observations, L2Options{});
  EXPECT_EQ(result.summary.pixels_rejected_degenerate, 1u);
  EXPECT_EQ(result.solved.at<std::uint8_t>(scene.observations.pixels[5]), 0);
  EXPECT_EQ(result.summary.pixels_solved, 15u);
}

TEST(HostLambertian, ThreadCountDoesNotChangeResults) {
  auto scene = make_scene(37, 23, 16, 7, true);
  // Some noise so that rounding order would show.
  std::mt19937 rng(9);
  std::normal_distribution<float> noise(0.0f, 0.01f);
  for (Eigen::Index i = 0; i < scene.observations.intensities.size(); ++i) {
    scene.observations.intensities.data()[i] += noise(rng);
  }
  for (const double t_low : {1.0, 0.6}) {
    L2Options one, four;
    one.threads = 1;
    four.threads = 4;
    one.t_low = four.t_low = t_low;
    one.shadow_threshold = four.shadow_threshold = t_low < 1 ? 0.001 : -1;
    const auto a = solve_lambertian(scene.observations, one);
    const auto b = solve_lambertian(scene.observations, four);
    EXPECT_TRUE(identical(a.normals, b.normals)) << "t_low " << t_low;
    EXPECT_TRUE(identical(a.albedo, b.albedo)) << "t_low " << t_low;
    EXPECT_TRUE(identical(a.residual, b.residual)) << "t_low " << t_low;
    EXPECT_TRUE(identical(a.solved, b.solved)) << "t_low " << t_low;
    EXPECT_EQ(a.summary.pixels_solved, b.summary.pixels_solved);
    EXPECT_EQ(a.summary.pixels_rejected_degenerate, b.summary.pixels_rejected_degenerate);
    EXPECT_EQ(a.summary.pixels_rejected_too_few_observations, b.summary.pixels_rejected_too_few_observations);
  }
}

// Pixels are solved four to a vector (solvers/pixel_lanes.hpp): dropping the
// first k pixels moves every other pixel to another lane beside other
// neighbours, and its normal, albedo, residual and predicted error must stay
// the same floats. Near and distant lights, noise, saturated and non-finite
// observations, a never-lit pixel, and each of the threshold and T_low.
TEST(HostLambertian, EveryPixelsAnswerIsTheSameInAnyLane) {
  auto scene = make_scene(13, 7, 15, 11, true);
  Observations& lit = scene.observations;
  std::mt19937 rng(4);
  std::normal_distribution<float> noise(0.0f, 0.01f);
  for (Eigen::Index i = 0; i < lit.intensities.size(); ++i) lit.intensities.data()[i] += noise(rng);
  for (Eigen::Index p = 0; p < lit.intensities.rows(); p += 5) lit.saturated(p, p % 15) = true;
  lit.intensities(9, 3) = std::numeric_limits<float>::quiet_NaN();
  lit.intensities(22, 7) = std::numeric_limits<float>::infinity();
  lit.intensities.row(30).setZero();
  NearLights near;
  near.led_positions_mm = 300.0 * lit.lights;
  near.points_mm = Eigen::MatrixX3d::Zero(lit.intensities.rows(), 3);
  for (std::size_t p = 0; p < lit.pixels.size(); ++p)
    near.points_mm.row(static_cast<Eigen::Index>(p)) << 2.0 * lit.pixels[p].x, 2.0 * lit.pixels[p].y, 0;
  for (const bool near_lights : {true, false}) {
    Observations full = lit;
    if (near_lights) full.near = near;
    for (const double t_low : {1.0, 0.7}) {
      SCOPED_TRACE(::testing::Message() << (near_lights ? "near" : "distant") << " lights, t_low " << t_low);
      L2Options options;
      options.threads = 1;
      options.t_low = t_low;
      options.shadow_threshold = t_low < 1 ? -1 : 0.01;
      options.confidence = ConfidenceOptions{};
      const SolveResult whole = solve_lambertian(full, options);
      ASSERT_GT(whole.summary.pixels_solved, 80u);
      for (const Eigen::Index dropped : {1, 2, 3}) {
        SCOPED_TRACE(dropped);
        Observations shifted = full;
        const Eigen::Index rest = full.intensities.rows() - dropped;
        shifted.intensities = full.intensities.bottomRows(rest);
        shifted.saturated = full.saturated.bottomRows(rest);
        if (near_lights) shifted.near->points_mm = near.points_mm.bottomRows(rest);
        shifted.pixels.erase(shifted.pixels.begin(), shifted.pixels.begin() + dropped);
        const SolveResult part = solve_lambertian(shifted, options);
        for (const cv::Point& at : shifted.pixels) {
          EXPECT_EQ(part.solved.at<std::uint8_t>(at), whole.solved.at<std::uint8_t>(at)) << at;
          EXPECT_EQ(part.normals.at<cv::Vec3f>(at), whole.normals.at<cv::Vec3f>(at)) << at;
          EXPECT_EQ(part.albedo.at<float>(at), whole.albedo.at<float>(at)) << at;
          EXPECT_EQ(part.residual.at<float>(at), whole.residual.at<float>(at)) << at;
          const float a = part.predicted_error.at<float>(at), b = whole.predicted_error.at<float>(at);
          EXPECT_TRUE(a == b || (std::isinf(a) && std::isinf(b))) << at << ": " << a << " vs " << b;
        }
      }
    }
  }
}

// Every l2 solve reads the saturation flags four pixels at a time, with or
// without its confidence: flags of another shape are refused by name, never read.
TEST(HostLambertian, RefusesSaturationFlagsOfAnotherShape) {
  auto scene = make_scene(5, 4, 9, 12, false);
  scene.observations.saturated = FlagMatrix::Constant(3, 9, false);
  L2Options options;
  options.shadow_threshold = 0.01;
  try {
    solve_lambertian(scene.observations, options);
    FAIL() << "flags of 3 rows for 20 pixels accepted";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("saturation flags are 3x9"), std::string::npos) << error.what();
  }
}

TEST(HostLambertian, OptionsCheckNamesTheField) {
  const auto message = [](const L2Options& options) {
    try {
      options.check();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  L2Options bad;
  bad.t_low = 0;
  EXPECT_NE(message(bad).find("t_low"), std::string::npos);
  bad = {};
  bad.t_low = 1.5;
  EXPECT_NE(message(bad).find("t_low"), std::string::npos);
  bad = {};
  bad.min_observations = 2;
  EXPECT_NE(message(bad).find("min_observations"), std::string::npos);
  bad = {};
  bad.threads = -1;
  EXPECT_NE(message(bad).find("threads"), std::string::npos);
  EXPECT_EQ(message(L2Options{}), "");
}

TEST(HostLambertian, SummaryJsonHasEveryField) {
  const auto scene = make_scene(5, 5, 6, 8, false);
  const auto json = solve_lambertian(scene.observations, L2Options{}).summary.to_json();
  for (const char* key : {"method", "pixels_in_mask", "pixels_solved", "pixels_rejected_too_few_observations",
                          "pixels_rejected_degenerate", "seconds", "message"}) {
    EXPECT_TRUE(json.contains(key)) << key;
  }
  EXPECT_EQ(json["pixels_solved"], 25);
}

}  // namespace
}  // namespace lightstage
