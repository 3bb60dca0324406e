// Real data from ../shared/data (skipped when it is not there): DiLiGenT's
// ball must reproduce the benchmark's least-squares baseline, and the UW cat
// (8-bit, 12 images) must load and solve.
#include "lightstage/host/eval/angular_error.hpp"
#include "lightstage/host/io/normal_map.hpp"
#include "lightstage/host/io/solve_output.hpp"
#include "lightstage/host/io/stack_io.hpp"
#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/solvers/auto.hpp"
#include "lightstage/host/solvers/bipolynomial.hpp"
#include "lightstage/host/solvers/lambertian.hpp"
#include "lightstage/host/solvers/monotonic.hpp"
#include "lightstage/host/solvers/robust.hpp"
#include "lightstage/testing/paths.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <chrono>
#include <iostream>

namespace lightstage {
namespace {

std::filesystem::path data_dir(const std::string& relative) {
  const auto shared = testing::shared_data_dir();
  if (shared.empty() || !std::filesystem::exists(shared / relative)) return {};
  return shared / relative;
}

TEST(HostRealData, DiligentBallReproducesTheLeastSquaresBaseline) {
  const auto ball = data_dir("diligent/ballPNG");
  if (ball.empty()) GTEST_SKIP() << "shared data not found";

  const auto start = std::chrono::steady_clock::now();
  const ImageStack stack = io::load_stack(ball);
  const auto loaded = std::chrono::steady_clock::now();
  ASSERT_EQ(stack.frames.size(), 96u);
  EXPECT_EQ(stack.width(), 612);
  EXPECT_EQ(stack.height(), 512);
  EXPECT_EQ(stack.frames.front().image.type(), CV_16UC3);
  ASSERT_TRUE(stack.ground_truth.has_value());
  EXPECT_EQ(cv::countNonZero(stack.mask), 15791);

  const Observations obs = make_observations(stack);
  const SolveResult result = solve_lambertian(obs, L2Options{});
  const auto solved = std::chrono::steady_clock::now();
  EXPECT_EQ(result.summary.pixels_solved, 15791u);

  const auto error = angular_error(result.normals, stack.ground_truth->normals, stack.mask).stats;
  EXPECT_EQ(error.count, 15791u);
  EXPECT_EQ(error.missing, 0u);
  EXPECT_NEAR(error.mean, 4.10, 0.1);

  // The benchmark's own published least-squares normals, pixel by pixel.
  const auto reference = io::read_normal_map(ball / "reference" / "Normal_l2.png");
  const auto match = angular_error(result.normals, reference.normals, stack.mask).stats;
  EXPECT_EQ(match.count, 15791u);
  // Our 16-bit normal map quantisation alone is ~0.001 degrees.
  EXPECT_LT(match.mean, 0.005);
  EXPECT_LT(match.max, 0.02);

  // Without the clamp the result is measurably different (4.17 published).
  RadiometryOptions unclamped;
  unclamped.clamp_to_one = false;
  const auto raw = solve_lambertian(make_observations(stack, unclamped), L2Options{});
  const auto raw_error = angular_error(raw.normals, stack.ground_truth->normals, stack.mask).stats;
  EXPECT_NEAR(raw_error.mean, 4.17, 0.1);
  EXPECT_GT(raw_error.mean - error.mean, 0.03);
  // A small convention slip (here: no clamp) is far outside the match tolerance.
  const auto raw_match = angular_error(raw.normals, reference.normals, stack.mask).stats;
  EXPECT_GT(raw_match.mean, 0.005);

  using seconds = std::chrono::duration<double>;
  std::cout << fmt::format(
      "ballPNG: mean {:.4f} median {:.4f} p90 {:.4f} max {:.4f} deg over {} px (unclamped {:.4f}); vs "
      "reference/Normal_l2.png: mean {:.5f} p90 {:.5f} max {:.5f} deg (unclamped: mean {:.4f}); load {:.2f} "
      "s, "
      "radiometry+solve {:.2f} s\n",
      error.mean, error.median, error.p90, error.max, error.count, raw_error.mean, match.mean, match.p90,
      match.max, raw_match.mean, seconds(loaded - start).count(), seconds(solved - loaded).count());

  // The written normal map evaluates to the same numbers.
  const auto out = testing::scratch_dir() / "ball";
  io::write_solve_outputs(out, result, ball);
  const auto reread = evaluate_normal_map(out / "normal.png", ball);
  EXPECT_NEAR(reread.mean, error.mean, 0.002);
  EXPECT_EQ(reread.count, 15791u);
}

// Issue 6 on real data: the general-reflectance methods with the
// dissertation's real-data shadow threshold (0.02), on every fourth mask pixel
// of the ball (a checkerboard-like subset, ~3,950 pixels, spread over the whole
// ball: the error depends on the distance from the centre). Published on the
// whole ball: ST14 (bi-polynomial) 1.74, learned methods 1.24–1.5. The ball's
// reflectance falls below Lambert's at grazing incidence (0.94 of the
// near-normal ratio at 60–70°, 0.87 at 70–80°), exactly the observations
// T_low keeps; with the published Lambertian start (falloff 0) that leaves a
// radial bias the alternation cannot undo with lights in a 43° cone
// (biquadratic 2.21 on the whole ball). The start with the object's
// incidence fall-off (the default; κ ≈ 0.382 estimated) removes it: whole ball
// biquadratic 1.23, bicubic 1.21, auto 1.37.
TEST(HostRealData, DiligentBallGeneralReflectanceMethods) {
  const auto ball = data_dir("diligent/ballPNG");
  if (ball.empty()) GTEST_SKIP() << "shared data not found";
  const auto start = std::chrono::steady_clock::now();
  ImageStack stack = io::load_stack(ball);
  ASSERT_TRUE(stack.ground_truth.has_value());
  for (int y = 0; y < stack.mask.rows; ++y) {
    for (int x = 0; x < stack.mask.cols; ++x) {
      if ((x + 2 * y) % 4 != 0) stack.mask.at<std::uint8_t>(y, x) = 0;
    }
  }
  const int subset = cv::countNonZero(stack.mask);
  EXPECT_GT(subset, 3700);
  EXPECT_LT(subset, 4200);
  const Observations obs = make_observations(stack);
  auto mean_error = [&](const SolveResult& result) {
    const auto stats = angular_error(result.normals, stack.ground_truth->normals, stack.mask).stats;
    EXPECT_EQ(stats.missing, 0u) << result.summary.message;
    return stats;
  };
  constexpr double kShadow = 0.02;
  RobustOptions robust;
  robust.shadow_threshold = kShadow;
  robust.threads = 2;
  BiPolynomialOptions biquadratic;
  biquadratic.shadow_threshold = kShadow;
  biquadratic.threads = 2;
  AutoOptions automatic;
  automatic.bipolynomial.shadow_threshold = automatic.monotonic.shadow_threshold = kShadow;
  automatic.threads = 2;
  const auto e_robust = mean_error(solve_robust(obs, robust));
  const SolveResult r_biquadratic = solve_bipolynomial(obs, biquadratic);
  const auto e_biquadratic = mean_error(r_biquadratic);
  const auto e_auto = mean_error(solve_auto(obs, automatic));
  const double kappa = r_biquadratic.parameters["falloff"]["kappa"].get<double>();
  BiPolynomialOptions published = biquadratic;
  published.falloff = 0.0;
  const auto e_published = mean_error(solve_bipolynomial(obs, published));
  // Monotonic is only loosely bounded: DiLiGenT's lights span 43° from the
  // view axis, and Algorithm 1's uniqueness needs the hemisphere.
  MonotonicOptions monotonic;
  monotonic.shadow_threshold = kShadow;
  monotonic.threads = 2;
  const cv::Mat azimuth = solve_robust(obs, robust).normals;
  const auto e_monotonic = mean_error(solve_monotonic(obs, monotonic, azimuth));
  std::cout << fmt::format(
      "ballPNG subset ({} px), mean / median deg: robust {:.3f} / {:.3f}, biquadratic {:.3f} / {:.3f}, auto "
      "{:.3f} / {:.3f} (fall-off {:.3f}), biquadratic with the Lambertian start {:.3f} / {:.3f}, monotonic "
      "(robust azimuth) {:.3f} / {:.3f} (ST14 published 1.74); {:.1f} s\n",
      subset, e_robust.mean, e_robust.median, e_biquadratic.mean, e_biquadratic.median, e_auto.mean,
      e_auto.median, kappa, e_published.mean, e_published.median, e_monotonic.mean, e_monotonic.median,
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  EXPECT_LT(e_robust.mean, 2.2);
  // The target: at least as accurate as ST14's published 1.74.
  EXPECT_LT(std::min(e_biquadratic.mean, e_auto.mean), 1.74);
  EXPECT_LT(e_biquadratic.mean, 1.5);
  EXPECT_LT(e_auto.mean, 1.6);
  // The ball is a dielectric: it darkens at grazing incidence (κ > 0), and the fall-off is what helps.
  EXPECT_GT(kappa, 0.2);
  EXPECT_LT(kappa, 0.6);
  EXPECT_GT(e_published.mean, e_biquadratic.mean + 0.5);
  // Monotonic: 3.95 measured (8.7 before the plateau descent); a loose bound so that a breakage shows.
  EXPECT_LT(e_monotonic.mean, 6.0);
}

TEST(HostRealData, UwCatLoadsAndSolves) {
  const auto cat = data_dir("uw-psm/cat");
  if (cat.empty()) GTEST_SKIP() << "shared data not found";
  const ImageStack stack = io::load_stack(cat);
  ASSERT_EQ(stack.frames.size(), 12u);
  EXPECT_EQ(stack.frames.front().image.depth(), CV_8U);
  EXPECT_EQ(stack.width(), 512);
  EXPECT_EQ(stack.height(), 340);
  EXPECT_FALSE(stack.mask.empty());
  EXPECT_FALSE(stack.ground_truth.has_value());
  L2Options options;
  options.shadow_threshold = 0.02;
  const auto result = solve_lambertian(make_observations(stack), options);
  EXPECT_GT(result.summary.pixels_solved, result.summary.pixels_in_mask * 9 / 10);
  // The cat faces the camera: most normals point toward it.
  cv::Mat z;
  cv::extractChannel(result.normals, z, 2);
  EXPECT_GT(cv::mean(z, result.solved)[0], 0.5);
}

}  // namespace
}  // namespace lightstage
