// The dome controller end to end, as three processes over the real protocol:
// lightstage-sim (virtual gpiochip + emulated camera strobe), lightstage-domed
// (the firmware on its sim: backend), and a host client. Checks are on the
// order and containment of the events the sim recorded with the firmware's
// own timestamps, never on tight wall-clock bounds.
#include "dome_fixture.hpp"

#include "lightstage/common/clock.hpp"
#include "lightstage/common/message_channel.hpp"
#include "lightstage/common/socket_link.hpp"
#include "lightstage/host/controller/sequences.hpp"
#include "lightstage/testing/paths.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <csignal>
#include <limits>
#include <thread>

namespace lightstage::testing {
namespace {

using std::chrono::milliseconds;
constexpr std::int64_t kNever = std::numeric_limits<std::int64_t>::max();

std::string led_line(std::uint32_t id) { return "LED" + std::to_string(id); }

bool overlaps(const Interval& a, std::int64_t start, std::int64_t end) {
  return a.start_ns < end && a.end_ns > start;
}

// Each step's LED is lit exactly once, from before its trigger to after its
// exposure window ends, and no other LED is lit during that window.
void expect_each_led_alone_in_its_window(const Timeline& timeline, const SequenceRun& run,
                                         const std::vector<std::uint32_t>& ids,
                                         const std::vector<std::pair<std::int64_t, std::int64_t>>& windows) {
  const auto leds = timeline.led_intervals();
  ASSERT_EQ(windows.size(), ids.size());
  for (std::size_t k = 0; k < ids.size(); ++k) {
    const std::string own = led_line(ids[k]);
    ASSERT_TRUE(leds.count(own)) << own << " never appears in the timeline";
    const auto& spans = leds.at(own);
    ASSERT_EQ(spans.size(), 1u) << own << " should be lit exactly once";
    const auto [window_start, window_end] = windows[k];
    EXPECT_LE(spans[0].start_ns, window_start) << own << " must be on before its trigger";
    EXPECT_GE(spans[0].end_ns, window_end) << own << " must stay on until its exposure ends";
    EXPECT_NE(spans[0].end_ns, kNever) << own << " was left on";
    // The firmware's step report and the sim's record carry the same stamps.
    EXPECT_EQ(run.steps[k].leds_on_ns(), spans[0].start_ns) << own;
    EXPECT_EQ(run.steps[k].leds_off_ns(), spans[0].end_ns) << own;
    for (const auto& [line, other] : leds) {
      if (line == own) continue;
      for (const auto& span : other) {
        EXPECT_FALSE(overlaps(span, window_start, window_end))
            << line << " lit during the exposure of " << own;
      }
    }
  }
}

TEST(ControllerIntegration, ClosedLoop96StepsEachLedOnlyInItsOwnExposure) {
  SimulatedDome dome({{}, {"--strobe-delay-us", "200", "--strobe-exposure-us", "2000"}, {}});
  auto client = dome.connect();
  ASSERT_TRUE(client->info().capabilities().strobe_input());
  ASSERT_EQ(client->info().led_count(), 96u);
  const auto ids = led_ids(client->info());
  OneLedPerStepOptions options;
  options.settle_us = 500;
  options.gap_us = 500;
  options.closed_loop = true;
  options.strobe_timeout_us = 500'000;
  const SequenceRun run = client->run_sequence(one_led_per_step(ids, options, 7));
  ASSERT_TRUE(run.ok()) << proto::Outcome_Name(run.done.outcome()) << ": " << run.done.detail();
  ASSERT_EQ(run.steps.size(), 96u);
  for (std::size_t k = 0; k < run.steps.size(); ++k) {
    const auto& e = run.steps[k];
    EXPECT_EQ(e.outcome(), proto::OK) << "step " << k;
    ASSERT_EQ(e.led_ids_size(), 1);
    EXPECT_EQ(e.led_ids(0), ids[k]);
    EXPECT_EQ(e.tag(), k);
    // Order within the step, from the firmware's own clock.
    EXPECT_LE(e.leds_on_ns(), e.trigger_ns());
    EXPECT_LT(e.trigger_ns(), e.strobe_rise_ns());
    EXPECT_LT(e.strobe_rise_ns(), e.strobe_fall_ns());
    EXPECT_LE(e.strobe_fall_ns(), e.leds_off_ns());
    EXPECT_GE(e.lateness_ns(), 0);
  }
  client.reset();
  const Timeline timeline = dome.stop_and_read_timeline();
  const auto triggers = timeline.intervals("TRIGGER");
  const auto strobes = timeline.intervals("STROBE");
  ASSERT_EQ(triggers.size(), 96u);
  ASSERT_EQ(strobes.size(), 96u);
  std::vector<std::pair<std::int64_t, std::int64_t>> windows;
  for (std::size_t k = 0; k < 96; ++k) {
    EXPECT_LT(triggers[k].start_ns, strobes[k].start_ns);
    windows.emplace_back(triggers[k].start_ns, strobes[k].end_ns);
  }
  expect_each_led_alone_in_its_window(timeline, run, ids, windows);
  EXPECT_TRUE(timeline.leds_left_on().empty());
}

TEST(ControllerIntegration, ShiftRegisterChainOpenLoop) {
  SimulatedDome dome({source_dir() / "hw/rigs/matrix-64.yaml", {}, {}});
  auto client = dome.connect();
  ASSERT_EQ(client->info().led_count(), 64u);
  EXPECT_FALSE(client->info().capabilities().strobe_input());
  const auto ids = led_ids(client->info());
  OneLedPerStepOptions options;
  options.settle_us = 300;
  options.exposure_us = 1500;
  options.gap_us = 300;
  const SequenceRun run = client->run_sequence(one_led_per_step(ids, options, 3));
  ASSERT_TRUE(run.ok()) << run.done.detail();
  ASSERT_EQ(run.steps.size(), 64u);
  client.reset();
  const Timeline timeline = dome.stop_and_read_timeline();
  const auto triggers = timeline.intervals("CAM_TRIG");
  ASSERT_EQ(triggers.size(), 64u);
  std::vector<std::pair<std::int64_t, std::int64_t>> windows;
  for (std::size_t k = 0; k < 64; ++k) {
    windows.emplace_back(triggers[k].start_ns,
                         triggers[k].start_ns + std::int64_t{options.exposure_us} * 1000);
  }
  for (const auto& e : timeline.entries()) {
    if (e.line.starts_with("LED")) {
      EXPECT_EQ(e.via, "leds") << e.line << " should be decoded from the chain";
    }
  }
  expect_each_led_alone_in_its_window(timeline, run, ids, windows);
  EXPECT_TRUE(timeline.leds_left_on().empty());
}

TEST(ControllerIntegration, SafetyLimitsHoldWhateverTheHostAsks) {
  const auto rig = rig_with_limits(source_dir() / "hw/rigs/sim-dome.yaml", 50'000, 0.2, 1'000'000,
                                   scratch_dir() / "tight.yaml");
  SimulatedDome dome({rig, {}, {}});
  auto client = dome.connect();

  // One step longer than the continuous on-time limit: refused up front.
  OneLedPerStepOptions too_long;
  too_long.exposure_us = 100'000;
  try {
    client->upload(one_led_per_step({4}, too_long, 1));
    FAIL() << "a step over max_on_us was accepted";
  } catch (const ControllerError& e) {
    EXPECT_EQ(e.code(), proto::Error::SAFETY_LIMIT) << e.what();
  }
  // Steps that each respect max_on_us but together exceed the duty cycle: refused.
  OneLedPerStepOptions short_steps;
  short_steps.exposure_us = 40'000;
  short_steps.gap_us = 0;
  short_steps.settle_us = 0;
  try {
    client->upload(one_led_per_step(std::vector<std::uint32_t>(10, 4), short_steps, 2));
    FAIL() << "a sequence over max_duty was accepted";
  } catch (const ControllerError& e) {
    EXPECT_EQ(e.code(), proto::Error::SAFETY_LIMIT) << e.what();
  }
  // A static SetLeds held far past the limit: the firmware darkens the LED itself.
  client->set_leds({{9, 1.0f}});
  std::this_thread::sleep_for(milliseconds(400));
  const proto::Status status = client->status();
  EXPECT_EQ(status.leds_on_size(), 0) << "LED 9 still on after 8x its on-time limit";
  EXPECT_EQ(status.state(), proto::Status::FAULT);
  EXPECT_FALSE(status.last_fault().empty());
  client.reset();
  const Timeline timeline = dome.stop_and_read_timeline();
  const auto spans = timeline.intervals("LED9");
  ASSERT_EQ(spans.size(), 1u);
  ASSERT_NE(spans[0].end_ns, kNever);
  // Enforced by the firmware (not by the host, which asked for 400 ms): well under the ask.
  EXPECT_LT(spans[0].end_ns - spans[0].start_ns, 150'000'000)
      << "on for " << (spans[0].end_ns - spans[0].start_ns);
  for (const auto& [line, led_spans] : timeline.led_intervals()) {
    if (line != "LED9") {
      EXPECT_TRUE(led_spans.empty()) << line << " was lit though refused";
    }
  }
}

TEST(ControllerIntegration, WatchdogDarkensTheDomeWhenHeartbeatsStop) {
  SimulatedDome dome({{}, {}, {"--watchdog-ms", "300"}});
  ControllerClientOptions options;
  options.watchdog_timeout_ms = 300;
  auto client = dome.connect(options);
  EXPECT_EQ(client->info().capabilities().watchdog_timeout_ms(), 300u);
  client->set_leds({{5, 1.0f}, {6, 1.0f}});
  client->stop_heartbeats();
  const std::int64_t silent_from = monotonic_now_ns();
  std::this_thread::sleep_for(milliseconds(1200));
  const Timeline timeline = dome.read_timeline();
  for (const std::string led : {"LED5", "LED6"}) {
    const auto spans = timeline.intervals(led);
    ASSERT_EQ(spans.size(), 1u) << led;
    ASSERT_NE(spans[0].end_ns, kNever) << led << " still lit after the watchdog timeout";
    EXPECT_GT(spans[0].end_ns, silent_from) << "darkened before the heartbeats stopped";
    // Within the timeout, plus the watchdog's own polling and this machine's scheduling noise.
    EXPECT_LT(spans[0].end_ns - silent_from, 300'000'000 + 500'000'000);
  }
  EXPECT_TRUE(dome.firmware().running()) << "the daemon keeps serving after a watchdog stop";
}

TEST(ControllerIntegration, KillingTheHostMidSequenceDarkensEveryLed) {
  SimulatedDome dome({{}, {}, {"--watchdog-ms", "300"}});
  ChildProcess host(bin_dir() / "lightstage",
                    {"ctl", "--controller", dome.controller_uri(), "--watchdog-ms", "300",
                     "run-test-sequence", "--loop", "open", "--exposure-us", "40000"},
                    scratch_dir() / "host.log");
  ASSERT_TRUE(host.wait_for_output("step   5", std::chrono::seconds(20))) << host.output();
  host.signal(SIGKILL);
  const std::int64_t killed_at = monotonic_now_ns();
  ASSERT_TRUE(host.wait(std::chrono::seconds(5)).has_value());
  std::this_thread::sleep_for(milliseconds(1000));
  const Timeline timeline = dome.read_timeline();
  EXPECT_TRUE(timeline.leds_left_on().empty()) << "LEDs left on after the host died";
  std::int64_t last_off = 0;
  std::size_t lit = 0;
  for (const auto& [line, spans] : timeline.led_intervals()) {
    for (const auto& span : spans) {
      last_off = std::max(last_off, span.end_ns);
      ++lit;
    }
  }
  EXPECT_GE(lit, 6u);
  EXPECT_LT(lit, 96u) << "the sequence should have been cut short";
  EXPECT_LT(last_off - killed_at, 300'000'000 + 500'000'000);
  // The daemon serves the next host.
  auto next = dome.connect();
  EXPECT_NE(next->status().state(), proto::Status::RUNNING);
}

TEST(ControllerIntegration, SigtermDarkensEveryLedAndExitsCleanly) {
  SimulatedDome dome;
  auto client = dome.connect();
  client->set_leds({{1, 1.0f}, {2, 1.0f}, {3, 1.0f}});
  EXPECT_EQ(client->status().leds_on_size(), 3);
  const Timeline timeline = dome.stop_and_read_timeline();
  for (const std::string led : {"LED1", "LED2", "LED3"}) {
    const auto spans = timeline.intervals(led);
    ASSERT_EQ(spans.size(), 1u) << led;
    EXPECT_NE(spans[0].end_ns, kNever) << led << " left on by SIGTERM";
  }
  EXPECT_TRUE(timeline.leds_left_on().empty());
}

TEST(ControllerIntegration, LostStrobeAbortsTheStepWithLedsDark) {
  SimulatedDome dome(
      {{}, {"--strobe-delay-us", "100", "--strobe-exposure-us", "1000", "--fault", "lose-strobe:3"}, {}});
  auto client = dome.connect();
  OneLedPerStepOptions options;
  options.closed_loop = true;
  options.strobe_timeout_us = 100'000;
  options.settle_us = 200;
  options.gap_us = 200;
  const std::vector<std::uint32_t> ids = {10, 11, 12, 13, 14, 15};
  const SequenceRun run = client->run_sequence(one_led_per_step(ids, options, 5));
  EXPECT_EQ(run.done.outcome(), proto::STROBE_TIMEOUT) << run.done.detail();
  ASSERT_FALSE(run.steps.empty());
  const auto& failed = run.steps.back();
  EXPECT_EQ(failed.outcome(), proto::STROBE_TIMEOUT);
  EXPECT_EQ(failed.step(), 2u) << "the third trigger lost its strobe";
  EXPECT_NE(failed.leds_off_ns(), 0);
  for (std::size_t k = 0; k + 1 < run.steps.size(); ++k) EXPECT_EQ(run.steps[k].outcome(), proto::OK);
  EXPECT_EQ(client->status().leds_on_size(), 0);
  client.reset();
  const Timeline timeline = dome.stop_and_read_timeline();
  EXPECT_TRUE(timeline.leds_left_on().empty());
  const auto spans = timeline.intervals(led_line(ids[failed.step()]));
  ASSERT_EQ(spans.size(), 1u);
  // Dark only after the strobe timeout ran out, not before.
  EXPECT_GE(spans[0].end_ns - failed.trigger_ns(), 100'000'000);
  for (std::size_t k = failed.step() + 1; k < ids.size(); ++k) {
    EXPECT_TRUE(timeline.intervals(led_line(ids[k])).empty()) << "step " << k << " ran after the abort";
  }
}

// The station darkens the dome from another thread while a sequence runs:
// the abort and the all-off get their own replies, the running sequence ends
// ABORTED_BY_HOST with no step after it, and nothing is left lit.
TEST(ControllerIntegration, AnAbortFromAnotherThreadEndsTheRunningSequence) {
  SimulatedDome dome;
  auto client = dome.connect();
  OneLedPerStepOptions options;
  options.exposure_us = 50'000;  // 96 steps of 50 ms: seconds left when the abort comes
  std::vector<std::uint32_t> ids;
  for (std::uint32_t id = 0; id < 96; ++id) ids.push_back(id);
  std::atomic<int> seen{0};
  std::atomic<bool> ended{false};
  std::thread darkener([&] {
    while (seen < 2 && !ended) std::this_thread::sleep_for(milliseconds(1));
    if (ended) return;
    client->abort();
    client->all_off();
  });
  SequenceRun run;
  try {
    run = client->run_sequence(one_led_per_step(ids, options, 7), [&](const proto::StepEvent&) { ++seen; });
  } catch (...) {
    ended = true;
    darkener.join();
    throw;
  }
  ended = true;
  darkener.join();
  EXPECT_EQ(run.done.outcome(), proto::ABORTED_BY_HOST) << run.done.detail();
  EXPECT_GE(run.steps.size(), 2u);
  EXPECT_LT(run.steps.size(), ids.size());
  EXPECT_EQ(client->status().leds_on_size(), 0);
  client.reset();
  const Timeline timeline = dome.stop_and_read_timeline();
  EXPECT_TRUE(timeline.leds_left_on().empty());
  for (std::size_t k = run.steps.size() + 1; k < ids.size(); ++k)
    EXPECT_TRUE(timeline.intervals(led_line(ids[k])).empty()) << "step " << k << " ran after the abort";
}

TEST(ControllerIntegration, MalformedFramesGetErrorsAndTheDaemonKeepsServing) {
  SimulatedDome dome;
  {
    MessageChannel raw(connect_socket_link(dome.controller_uri(), std::chrono::seconds(5)));
    // Garbage, then a well-framed payload that is not a HostMessage.
    const std::vector<std::uint8_t> garbage = {0x00, 0xff, 0x13, 0x37, 'L', 'x', 0x42};
    raw.link().write(garbage);
    const std::vector<std::uint8_t> junk = {0xff, 0xff, 0xff, 0xff, 0x0f};
    raw.link().write(protocol::encode_frame(junk));
    bool saw_error = false;
    proto::ControllerMessage reply;
    for (int i = 0; i < 4 && !saw_error; ++i) {
      if (!raw.receive(reply, milliseconds(2000))) break;
      saw_error = reply.has_error() && reply.error().code() == proto::Error::MALFORMED_FRAME;
    }
    EXPECT_TRUE(saw_error) << "no MALFORMED_FRAME error reply";
    // A command before Hello is refused, then Hello still works on the same link.
    proto::HostMessage status;
    status.set_request_id(9);
    status.mutable_status();
    raw.send(status);
    // Skip further error reports about the damaged bytes (request id 0).
    do {
      ASSERT_TRUE(raw.receive(reply, milliseconds(2000)));
    } while (reply.request_id() == 0);
    EXPECT_EQ(reply.request_id(), 9u);
    ASSERT_TRUE(reply.has_error());
    EXPECT_EQ(reply.error().code(), proto::Error::NOT_NEGOTIATED);
    proto::HostMessage hello;
    hello.set_request_id(10);
    hello.mutable_hello()->set_protocol_version(kProtocolVersion);
    hello.mutable_hello()->set_min_protocol_version(kProtocolVersion);
    raw.send(hello);
    ASSERT_TRUE(raw.receive(reply, milliseconds(2000)));
    EXPECT_TRUE(reply.has_info());
  }
  // A host speaking only a future protocol is told so (once the daemon has
  // seen the previous connection go: until then it answers BUSY).
  for (int attempt = 0;; ++attempt) {
    MessageChannel raw(connect_socket_link(dome.controller_uri(), std::chrono::seconds(5)));
    proto::HostMessage hello;
    hello.set_request_id(1);
    hello.mutable_hello()->set_protocol_version(99);
    hello.mutable_hello()->set_min_protocol_version(98);
    raw.send(hello);
    proto::ControllerMessage reply;
    ASSERT_TRUE(raw.receive(reply, milliseconds(2000)));
    ASSERT_TRUE(reply.has_error());
    if (reply.error().code() == proto::Error::BUSY && attempt < 50) {
      std::this_thread::sleep_for(milliseconds(50));
      continue;
    }
    EXPECT_EQ(reply.error().code(), proto::Error::VERSION_MISMATCH);
    break;
  }
  // The next host is served once the daemon has seen that one go (BUSY until then).
  for (int attempt = 0;; ++attempt) {
    try {
      auto client = dome.connect();
      EXPECT_EQ(client->info().led_count(), 96u);
      break;
    } catch (const Error& e) {  // refused: BUSY, then the daemon hangs up
      ASSERT_LT(attempt, 50) << "still refused: " << e.what();
      std::this_thread::sleep_for(milliseconds(50));
    }
  }
  EXPECT_TRUE(dome.firmware().running());
}

}  // namespace
}  // namespace lightstage::testing
