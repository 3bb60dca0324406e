// Speed of the first slice: rendering a stack, radiometry, and the Lambertian
// solver's two paths (shared pseudo-inverse vs per-pixel selection) at 1 and 2
// threads, on a 512x512 simulated sphere under the 96-LED default dome.
//   build/bench/bench_lightstage
#include "lightstage/common/rig.hpp"
#include "lightstage/host/radiometry.hpp"
#include "lightstage/host/solvers/lambertian.hpp"
#include "lightstage/sim/simulate.hpp"

#include <benchmark/benchmark.h>

namespace lightstage {
namespace {

sim::SimulateOptions sphere_options(int size) {
  sim::SimulateOptions options;
  options.scene = "sphere";
  options.light_model = sim::LightModel::kDistant;
  options.width = size;
  options.height = size;
  return options;
}

const Observations& sphere_observations() {
  static const Observations observations =
      make_observations(sim::simulate_stack(load_rig(default_rig_path()), sphere_options(512)));
  return observations;
}

void BM_SimulateSphere256(benchmark::State& state) {
  const Rig rig = load_rig(default_rig_path());
  sim::SimulateOptions options = sphere_options(256);
  options.threads = static_cast<int>(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(sim::simulate_stack(rig, options));
}
BENCHMARK(BM_SimulateSphere256)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_SolveL2AllLights(benchmark::State& state) {
  const Observations& observations = sphere_observations();
  L2Options options;
  options.threads = static_cast<int>(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(solve_lambertian(observations, options));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(observations.pixel_count()));
}
BENCHMARK(BM_SolveL2AllLights)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_SolveL2ShadowThreshold(benchmark::State& state) {
  const Observations& observations = sphere_observations();
  L2Options options;
  options.shadow_threshold = 0.02;
  options.threads = static_cast<int>(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(solve_lambertian(observations, options));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(observations.pixel_count()));
}
BENCHMARK(BM_SolveL2ShadowThreshold)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace lightstage

BENCHMARK_MAIN();
