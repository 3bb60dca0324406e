// Surface speed (issue 7): integrating a 1-megapixel normal map over a
// non-rectangular mask (Poisson, multigrid-preconditioned CG), the same with
// discontinuity reweighting, Frankot–Chellappa on the full rectangle, and
// depth–normal fusion. Run: build/bench/bench_surface
#include "lightstage/host/surface/fusion.hpp"
#include "lightstage/host/surface/integration.hpp"

#include <benchmark/benchmark.h>

#include <cmath>

namespace lightstage::surface {
namespace {

struct Scene {
  cv::Mat normals, mask, depth;
  CameraModel camera;
};

// Gaussian bumps on a disk, n×n pixels, exact normals.
const Scene& scene(int n) {
  static Scene s;
  if (s.mask.rows == n) return s;
  s.camera = CameraModel::orthographic(cv::Size(n, n), 1.0);
  s.normals = cv::Mat::zeros(n, n, CV_32FC3);
  s.mask = cv::Mat::zeros(n, n, CV_8UC1);
  s.depth = cv::Mat::zeros(n, n, CV_32FC1);
  const double bumps[4][4] = {
      {0.3, 0.4, 0.12, 0.15}, {0.65, 0.55, 0.1, 0.1}, {0.5, 0.25, 0.08, 0.06}, {0.5, 0.5, 0.3, 0.2}};
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) {
      const double x = static_cast<double>(c) / n, y = static_cast<double>(r) / n;
      if ((x - 0.5) * (x - 0.5) + (y - 0.5) * (y - 0.5) > 0.23) continue;
      double h = 0, hx = 0, hy = 0;
      for (const auto& b : bumps) {
        const double dx = x - b[0], dy = y - b[1], s2 = b[2] * b[2];
        const double e = b[3] * n * std::exp(-(dx * dx + dy * dy) / (2 * s2));
        h += e;
        hx += -e * dx / s2 / n;  // per pixel
        hy += -e * dy / s2 / n;
      }
      // Rows grow downward: ∂h/∂y_up = −hy.
      const Vec3 normal = Vec3(-hx, hy, 1).normalized();
      s.normals.at<cv::Vec3f>(r, c) = cv::Vec3f(
          static_cast<float>(normal.x()), static_cast<float>(normal.y()), static_cast<float>(normal.z()));
      s.mask.at<std::uint8_t>(r, c) = 255;
      s.depth.at<float>(r, c) = static_cast<float>(h);
    }
  }
  return s;
}

void BM_Poisson(benchmark::State& state) {
  const Scene& s = scene(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(integrate_normals(s.normals, s.mask, s.camera).depth.data);
  state.counters["pixels"] = cv::countNonZero(s.mask);
}
BENCHMARK(BM_Poisson)->Arg(256)->Arg(1024)->Unit(benchmark::kMillisecond);

void BM_PoissonDiscontinuityPreserving(benchmark::State& state) {
  const Scene& s = scene(static_cast<int>(state.range(0)));
  IntegrationOptions options;
  options.preserve_discontinuities = true;
  for (auto _ : state)
    benchmark::DoNotOptimize(integrate_normals(s.normals, s.mask, s.camera, options).depth.data);
}
BENCHMARK(BM_PoissonDiscontinuityPreserving)->Arg(1024)->Unit(benchmark::kMillisecond);

void BM_FrankotChellappa(benchmark::State& state) {
  const Scene& s = scene(static_cast<int>(state.range(0)));
  IntegrationOptions options;
  options.method = IntegrationMethod::kFrankotChellappa;
  const cv::Mat full(s.mask.size(), CV_8UC1, cv::Scalar(255));
  for (auto _ : state)
    benchmark::DoNotOptimize(integrate_normals(s.normals, full, s.camera, options).depth.data);
}
BENCHMARK(BM_FrankotChellappa)->Arg(1024)->Unit(benchmark::kMillisecond);

void BM_Fusion(benchmark::State& state) {
  const Scene& s = scene(static_cast<int>(state.range(0)));
  for (auto _ : state)
    benchmark::DoNotOptimize(fuse_depth_normals(s.depth, s.mask, s.normals, s.mask, s.camera).depth.data);
}
BENCHMARK(BM_Fusion)->Arg(1024)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace lightstage::surface

BENCHMARK_MAIN();
