// bench_sequencer_lateness: how late the controller's deadlines are on this
// machine. Starts lightstage-sim and lightstage-domed as on a dome, runs the
// 96-step one-LED-per-step sequence open and closed loop several times, and
// prints the step lateness (median, p99, max) reported by the firmware next to
// the plan's timing and next to a reference measured in this process: the
// lateness of bare clock_nanosleep wake-ups on the same machine at the same
// time (the floor no sequencer can beat without a real-time kernel).
//
//   build/bench/bench_sequencer_lateness [runs=5]
#include "dome_fixture.hpp"

#include "lightstage/common/clock.hpp"
#include "lightstage/host/controller/sequences.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdlib>
#include <vector>

namespace {

using namespace lightstage;

LatenessStats bare_sleep_lateness(int samples, std::int64_t period_ns) {
  MonotonicClock clock;
  std::vector<proto::StepEvent> fake(static_cast<std::size_t>(samples));
  std::int64_t deadline = clock.now_ns() + period_ns;
  for (auto& e : fake) {
    clock.sleep_until(deadline);
    e.set_lateness_ns(clock.now_ns() - deadline);
    deadline += period_ns;
  }
  return lateness_stats(fake);
}

void print_row(const std::string& what, const LatenessStats& s, double plan_ms) {
  fmt::print("{:<34} {:>6} {:>12.3f} {:>12.3f} {:>12.3f} {:>12.2f}\n", what, s.steps, s.median_ns / 1e3,
             s.p99_ns / 1e3, s.max_ns / 1e3, plan_ms);
}

}  // namespace

int main(int argc, char** argv) {
  const int runs = argc > 1 ? std::max(1, std::atoi(argv[1])) : 5;
  testing::SimulatedDome dome({{}, {"--strobe-delay-us", "200", "--strobe-exposure-us", "2000"}, {}});
  auto client = dome.connect();
  const auto ids = led_ids(client->info());
  fmt::print("firmware {}, rig '{}', {} LEDs, realtime scheduling: {}\n", client->info().firmware_version(),
             client->info().rig_name(), ids.size(), client->info().capabilities().realtime() ? "yes" : "no");
  fmt::print("{:<34} {:>6} {:>12} {:>12} {:>12} {:>12}\n", "lateness (us)", "steps", "median", "p99", "max",
             "plan ms/step");
  for (const bool closed : {false, true}) {
    OneLedPerStepOptions options;
    options.settle_us = 500;
    options.exposure_us = 2000;
    options.gap_us = 500;
    options.closed_loop = closed;
    std::vector<proto::StepEvent> all;
    for (int r = 0; r < runs; ++r) {
      const SequenceRun run =
          client->run_sequence(one_led_per_step(ids, options, static_cast<std::uint32_t>(r + 1)));
      if (!run.ok()) {
        fmt::print(stderr, "run {} ended {}: {}\n", r, proto::Outcome_Name(run.done.outcome()),
                   run.done.detail());
        return 1;
      }
      all.insert(all.end(), run.steps.begin(), run.steps.end());
    }
    const double plan_ms = (options.settle_us + options.exposure_us + options.gap_us) / 1e3 +
                           (closed ? 0.2 : 0.0);  // closed loop waits for the strobe delay too
    print_row(closed ? "sequencer, closed loop (strobe)" : "sequencer, open loop", lateness_stats(all),
              plan_ms);
  }
  const LatenessStats reference = bare_sleep_lateness(96 * runs, 1'000'000);
  print_row("reference: bare clock_nanosleep", reference, 1.0);
  return 0;
}
