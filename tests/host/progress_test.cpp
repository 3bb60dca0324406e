#include "lightstage/host/progress.hpp"

#include "lightstage/host/solvers/auto.hpp"
#include "lightstage/host/solvers/bipolynomial.hpp"
#include "lightstage/host/solvers/lambertian.hpp"
#include "lightstage/host/solvers/robust.hpp"
#include "lightstage/host/surface/fusion.hpp"
#include "lightstage/host/surface/integration.hpp"
#include "synthetic.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <thread>
#include <vector>

namespace lightstage {
namespace {

using namespace std::chrono_literals;

TEST(Progress, LineShowsShareCountAndEstimate) {
  Progress p("solve", 200, "px", OutputMode::kHuman, nullptr);
  EXPECT_FALSE(p.visible());
  p.advance(50);
  EXPECT_EQ(p.line(2s), "solve   25% 50/200 px  ETA 6.0 s");
  p.advance(150);
  EXPECT_EQ(p.line(8s), "solve  100% 200/200 px  ETA 0.0 s");
}

TEST(Progress, NoEstimateBeforeThereIsARate) {
  Progress p("capture", 96, "frames", OutputMode::kHuman, nullptr);
  EXPECT_EQ(p.line(0s), "capture    0% 0/96 frames  ETA --");
  Progress unknown("render", 0, "frames", OutputMode::kHuman, nullptr);
  unknown.advance(3);
  EXPECT_EQ(unknown.line(90s), "render  3 frames  1m30s");
}

TEST(Progress, SilentWhenNotATerminalOrQuietOrJson) {
  std::FILE* file = std::tmpfile();
  ASSERT_NE(file, nullptr);
  for (const OutputMode mode : {OutputMode::kHuman, OutputMode::kQuiet, OutputMode::kJson}) {
    Progress p("x", 10, "items", mode, file);
    EXPECT_FALSE(p.visible());
    p.advance(10);
  }
  EXPECT_EQ(std::ftell(file), 0) << "progress written to a file";
  std::fclose(file);
}

TEST(Progress, CountsFromManyThreads) {
  Progress p("x", 8000, "items", OutputMode::kQuiet, nullptr);
  std::vector<std::thread> workers;
  for (int t = 0; t < 8; ++t) {
    workers.emplace_back([&] {
      for (int i = 0; i < 1000; ++i) p.advance();
    });
  }
  for (auto& w : workers) w.join();
  EXPECT_EQ(p.done(), 8000u);
}

TEST(Progress, ShareOnlyWithoutAUnit) {
  Progress p("integrate", 1000, "", OutputMode::kHuman, nullptr);
  p.advance_to(250);
  EXPECT_EQ(p.line(1s), "integrate   25%  ETA 3.0 s");
  p.advance_to(100);  // never goes back
  EXPECT_EQ(p.done(), 250u);
  p.advance_to(1000);
  EXPECT_EQ(p.line(4s), "integrate  100%  ETA 0.0 s");
}

// Every solver's progress hears of every pixel exactly once, from any number of
// threads, and reporting does not change the result.
TEST(SolverProgress, EveryPixelIsCountedOnce) {
  const auto scene = testing::make_scene(53, 41, 20, 3, /*clamp_shadows=*/true);
  const std::size_t pixels = scene.observations.pixel_count();
  std::atomic<std::size_t> counted{0};
  const SolveProgress count = [&counted](std::size_t items) { counted += items; };
  // Solves with and without a progress report: every pixel counted once, the same normals.
  auto expect_counted = [&](auto options, auto solve, const char* what) {
    const SolveResult without = solve(scene.observations, options);
    options.progress = count;
    const SolveResult with = solve(scene.observations, options);
    EXPECT_EQ(counted.exchange(0), pixels) << what;
    EXPECT_EQ(cv::norm(with.normals, without.normals, cv::NORM_INF), 0.0) << what;
  };
  for (const double t_low : {1.0, 0.5}) {  // l2's shared pseudo-inverse and its per-pixel path
    L2Options l2;
    l2.threads = 3;
    l2.t_low = t_low;
    expect_counted(l2, solve_lambertian, "l2");
  }
  RobustOptions robust;
  robust.threads = 3;
  expect_counted(robust, solve_robust, "robust");
  BiPolynomialOptions bipolynomial;
  bipolynomial.threads = 2;
  expect_counted(bipolynomial, solve_bipolynomial, "biquadratic");
  AutoOptions automatic;
  automatic.threads = 2;
  expect_counted(automatic, solve_auto, "auto");
}

// A hemisphere's normals over a disk mask.
void hemisphere(int size, cv::Mat& normals, cv::Mat& mask) {
  normals = cv::Mat::zeros(size, size, CV_32FC3);
  mask = cv::Mat::zeros(size, size, CV_8UC1);
  const double c = (size - 1) / 2.0, radius = 0.45 * size;
  for (int r = 0; r < size; ++r) {
    for (int col = 0; col < size; ++col) {
      const double x = (col - c) / radius, y = (c - r) / radius, rr = x * x + y * y;
      if (rr >= 0.9) continue;
      normals.at<cv::Vec3f>(r, col) =
          cv::Vec3f(static_cast<float>(x), static_cast<float>(y), static_cast<float>(std::sqrt(1 - rr)));
      mask.at<std::uint8_t>(r, col) = 255;
    }
  }
}

// The surface solvers report a rising share that ends at 1, and reporting changes nothing.
TEST(SurfaceProgress, RisesToOneAndChangesNothing) {
  cv::Mat normals, mask;
  hemisphere(64, normals, mask);
  const auto camera = surface::CameraModel::orthographic(mask.size());
  for (const bool reweight : {false, true}) {
    surface::IntegrationOptions options;
    options.preserve_discontinuities = reweight;
    std::vector<double> seen;
    const auto with =
        surface::integrate_normals(normals, mask, camera, options, [&seen](double f) { seen.push_back(f); });
    const auto without = surface::integrate_normals(normals, mask, camera, options);
    // At least one report per reweighting round (more while conjugate gradients iterate).
    ASSERT_GE(seen.size(), reweight ? static_cast<std::size_t>(options.reweight_iterations + 1) : 1u);
    for (std::size_t i = 1; i < seen.size(); ++i) EXPECT_GT(seen[i], seen[i - 1]);
    EXPECT_GE(seen.front(), 0.0);
    EXPECT_EQ(seen.back(), 1.0);
    EXPECT_EQ(cv::norm(with.depth, without.depth, cv::NORM_INF), 0.0);
  }
  const cv::Mat prior(mask.size(), CV_32FC1, cv::Scalar::all(5.0));
  std::vector<double> seen;
  surface::fuse_depth_normals(prior, mask, normals, mask, camera, {},
                              [&seen](double f) { seen.push_back(f); });
  ASSERT_FALSE(seen.empty());
  EXPECT_EQ(seen.back(), 1.0);
}

}  // namespace
}  // namespace lightstage
