// Speed of every `solve --method` on one stack, in one run: pixels per second
// at 2 threads, with l2 and a plain read of the observation matrix (the floor
// any solver pays) as the yardsticks, the radiometry that builds that matrix
// from the frames, and the confidence every result gets (and l2's own under
// near lights). The stack: a
// simulated Cook–Torrance sphere under the 96-LED default dome (distant
// lights), 192x192.
//   build/bench/bench_photometric --benchmark_counters_tabular=true
#include "lightstage/common/rig.hpp"
#include "lightstage/host/near_lights.hpp"
#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/reflectance/bipolynomial_model.hpp"
#include "lightstage/host/solvers/auto.hpp"
#include "lightstage/host/solvers/bipolynomial.hpp"
#include "lightstage/host/solvers/lambertian.hpp"
#include "lightstage/host/solvers/low_rank.hpp"
#include "lightstage/host/solvers/monotonic.hpp"
#include "lightstage/host/solvers/normal_confidence.hpp"
#include "lightstage/host/solvers/robust.hpp"
#include "lightstage/host/solvers/sparse_regression.hpp"
#include "lightstage/sim/simulate.hpp"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

namespace lightstage {
namespace {

constexpr int kThreads = 2;

// The sphere, grey or in colour (a tint per patch: what the chroma costs).
ImageStack simulated_sphere(const std::string& colour) {
  sim::SimulateOptions options;
  options.scene = "sphere";
  options.material = "cook-torrance:roughness=0.3,ks=0.5";
  options.colour = colour;
  options.light_model = sim::LightModel::kDistant;
  options.width = options.height = 192;
  return sim::simulate_stack(load_rig(default_rig_path()), options);
}

const ImageStack& images() {
  static const ImageStack stack = simulated_sphere("");
  return stack;
}

const ImageStack& colour_images() {
  static const ImageStack stack = simulated_sphere("patches");
  return stack;
}

const Observations& stack() {
  static const Observations observations = make_observations(images());
  return observations;
}

// l2's pixels/s in this process (best of 20 solves), the yardstick of the vs_l2 column.
double l2_pixels_per_second() {
  static const double rate = [] {
    L2Options options;
    options.threads = kThreads;
    double best = 1e30;
    for (int i = 0; i < 20; ++i) {
      const auto start = std::chrono::steady_clock::now();
      benchmark::DoNotOptimize(solve_lambertian(stack(), options));
      best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    return static_cast<double>(stack().pixel_count()) / best;
  }();
  return rate;
}

void report(benchmark::State& state) {
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(stack().pixel_count()));
  state.counters["images"] = static_cast<double>(stack().image_count());
  // pixels/s ÷ l2's pixels/s, same run.
  state.counters["vs_l2"] =
      benchmark::Counter(static_cast<double>(stack().pixel_count()) / l2_pixels_per_second(),
                         benchmark::Counter::kIsIterationInvariantRate);
}

// Reading every observation once (what any solver must at least do), on 2 threads.
void BM_ReadStack(benchmark::State& state) {
  const Observations& obs = stack();
  for (auto _ : state) {
    double sums[kThreads] = {};
    std::vector<std::thread> workers;
    const Eigen::Index rows = obs.intensities.rows();
    for (int t = 0; t < kThreads; ++t) {
      workers.emplace_back([&, t] {
        const Eigen::Index begin = rows * t / kThreads, end = rows * (t + 1) / kThreads;
        sums[t] = obs.intensities.middleRows(begin, end - begin).cast<double>().sum();
      });
    }
    for (auto& w : workers) w.join();
    benchmark::DoNotOptimize(sums[0] + sums[1]);
  }
  report(state);
}
BENCHMARK(BM_ReadStack)->Unit(benchmark::kMillisecond)->UseRealTime();

// Radiometry: 16-bit frames to the observation matrix, on 2 threads (every
// solve pays it once, after decoding the images).
void BM_MakeObservations(benchmark::State& state) {
  RadiometryOptions options;
  options.threads = kThreads;
  for (auto _ : state) benchmark::DoNotOptimize(make_observations(images(), options));
  report(state);
}
BENCHMARK(BM_MakeObservations)->Unit(benchmark::kMillisecond)->UseRealTime();

// The same from 16-bit RGB frames, each pixel's chroma (medians of its
// channels' ratios) included.
void BM_MakeObservationsColour(benchmark::State& state) {
  RadiometryOptions options;
  options.threads = kThreads;
  for (auto _ : state) benchmark::DoNotOptimize(make_observations(colour_images(), options));
  report(state);
}
BENCHMARK(BM_MakeObservationsColour)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_L2(benchmark::State& state) {
  L2Options options;
  options.threads = kThreads;
  for (auto _ : state) benchmark::DoNotOptimize(solve_lambertian(stack(), options));
  report(state);
}
BENCHMARK(BM_L2)->Unit(benchmark::kMillisecond)->UseRealTime();

// The stack under near lights (the rig's LEDs, the surface on the plane z = 0,
// 0.2 mm a pixel): l2 solves it pixel by pixel, each with its own directions.
const Observations& near_stack() {
  static const Observations observations = [] {
    Observations near = stack();
    const Rig rig = load_rig(default_rig_path());
    NearLights lights;
    lights.led_positions_mm.resize(static_cast<Eigen::Index>(rig.leds.size()), 3);
    for (std::size_t j = 0; j < rig.leds.size(); ++j)
      lights.led_positions_mm.row(static_cast<Eigen::Index>(j)) = rig.leds[j].position_mm.transpose();
    lights.object_centre_mm = rig.object_position_mm;
    lights.points_mm.resize(static_cast<Eigen::Index>(near.pixel_count()), 3);
    for (std::size_t p = 0; p < near.pixel_count(); ++p)
      lights.points_mm.row(static_cast<Eigen::Index>(p)) << 0.2 * (near.pixels[p].x - near.size.width / 2),
          0.2 * (near.pixels[p].y - near.size.height / 2), 0.0;
    near.near = lights;
    return near;
  }();
  return observations;
}

// l2 under near lights and then the confidence's separate pass, as every
// other method's result gets it; against BM_L2NearPredicting, the same
// numbers with each pixel's directions computed once.
void BM_L2NearThenConfidence(benchmark::State& state) {
  L2Options l2;
  l2.threads = kThreads;
  ConfidenceOptions confidence;
  confidence.threads = kThreads;
  for (auto _ : state) {
    const SolveResult result = solve_lambertian(near_stack(), l2);
    benchmark::DoNotOptimize(predict_normal_error(near_stack(), result, confidence));
  }
  report(state);
}
BENCHMARK(BM_L2NearThenConfidence)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_L2NearPredicting(benchmark::State& state) {
  L2Options l2;
  l2.threads = kThreads;
  l2.confidence = ConfidenceOptions{};
  l2.confidence->threads = kThreads;
  for (auto _ : state) benchmark::DoNotOptimize(solve_lambertian(near_stack(), l2));
  report(state);
}
BENCHMARK(BM_L2NearPredicting)->Unit(benchmark::kMillisecond)->UseRealTime();

// The confidence every method's result gets (solve_with), here of l2's.
void BM_Confidence(benchmark::State& state) {
  L2Options l2;
  l2.threads = kThreads;
  const SolveResult result = solve_lambertian(stack(), l2);
  ConfidenceOptions options;
  options.threads = kThreads;
  for (auto _ : state) benchmark::DoNotOptimize(predict_normal_error(stack(), result, options));
  report(state);
}
BENCHMARK(BM_Confidence)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Robust(benchmark::State& state) {
  RobustOptions options;
  options.threads = kThreads;
  options.estimator = static_cast<RobustEstimator>(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(solve_robust(stack(), options));
  report(state);
  state.SetLabel(robust_estimator_name(options.estimator));
}
BENCHMARK(BM_Robust)
    ->Arg(static_cast<int>(RobustEstimator::kIrlsL1))
    ->Arg(static_cast<int>(RobustEstimator::kRansac))
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The published robust family next to l2 and robust (issue 14), same stack, same run.
void BM_Rpca(benchmark::State& state) {
  RpcaOptions options;
  options.threads = kThreads;
  for (auto _ : state) benchmark::DoNotOptimize(solve_rpca(stack(), options));
  report(state);
}
BENCHMARK(BM_Rpca)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_L1(benchmark::State& state) {
  L1Options options;
  options.threads = kThreads;
  for (auto _ : state) benchmark::DoNotOptimize(solve_l1(stack(), options));
  report(state);
}
BENCHMARK(BM_L1)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Sbl(benchmark::State& state) {
  SblOptions options;
  options.threads = kThreads;
  for (auto _ : state) benchmark::DoNotOptimize(solve_sbl(stack(), options));
  report(state);
}
BENCHMARK(BM_Sbl)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_BiPolynomial(benchmark::State& state) {
  BiPolynomialOptions options;
  options.threads = kThreads;
  options.order = static_cast<int>(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(solve_bipolynomial(stack(), options));
  report(state);
  state.SetLabel(bipolynomial_name(options.order));
}
BENCHMARK(BM_BiPolynomial)->DenseRange(1, 3)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Monotonic(benchmark::State& state) {
  MonotonicOptions options;
  options.threads = kThreads;
  for (auto _ : state) benchmark::DoNotOptimize(solve_monotonic(stack(), options));
  report(state);
}
BENCHMARK(BM_Monotonic)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

void BM_Auto(benchmark::State& state) {
  AutoOptions options;
  options.threads = kThreads;
  for (auto _ : state) benchmark::DoNotOptimize(solve_auto(stack(), options));
  report(state);
}
BENCHMARK(BM_Auto)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

}  // namespace
}  // namespace lightstage

BENCHMARK_MAIN();
