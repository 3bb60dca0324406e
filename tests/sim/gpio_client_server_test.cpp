// The `sim:` backend against a real lightstage-sim server in this process:
// GpioService behind a ServiceHost on a Unix socket, connect_sim_chip() as the
// firmware uses it. Checks order and containment, never tight timings.
#include "gpio_test_support.hpp"
#include "lightstage/common/clock.hpp"
#include "lightstage/common/framing.hpp"
#include "lightstage/common/message_channel.hpp"
#include "lightstage/common/socket_link.hpp"
#include "lightstage/proto/sim_gpio.pb.h"
#include "lightstage/sim/gpio/gpio_service.hpp"
#include "lightstage/sim/gpio/service_host.hpp"
#include "lightstage/sim/gpio/sim_chip.hpp"
#include "lightstage/testing/paths.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <thread>

namespace lightstage::sim::gpio {
namespace {

using lightstage::gpio::GpioError;
using testing::entries_for;
using testing::shipped_rig;

constexpr std::int64_t kMs = 1'000'000;

std::string gpio_error_of(const std::function<void()>& action) {
  try {
    action();
  } catch (const GpioError& e) {
    return e.what();
  }
  return "(no GpioError)";
}

class SimServerTest : public ::testing::Test {
 protected:
  void start(const std::string& rig_name = "sim-dome", std::int64_t delay_ns = 2 * kMs,
             std::int64_t exposure_ns = 5 * kMs) {
    static std::atomic<int> counter{0};
    socket_path = lightstage::testing::socket_dir() / ("gpio-" + std::to_string(counter++) + ".sock");
    address = "unix:" + socket_path.string();
    const Rig rig = shipped_rig(rig_name);
    VirtualChipOptions options = chip_options_for(rig);
    options.strobe_delay_ns = delay_ns;
    options.strobe_exposure_ns = exposure_ns;
    chip = std::make_shared<VirtualChip>(layout_from_rig(rig), options);
    service = std::make_shared<GpioService>(chip);
    host.add(listen_socket_link(address), service);
  }
  void TearDown() override { host.stop(); }

  std::filesystem::path socket_path;
  std::string address;
  std::shared_ptr<VirtualChip> chip;
  std::shared_ptr<GpioService> service;
  ServiceHost host;
};

TEST_F(SimServerTest, TheClientSeesTheRigLinesByName) {
  start();
  const auto gpio = connect_sim_chip(address);
  const auto info = gpio->info();
  EXPECT_EQ(info.label, "lightstage-sim");
  ASSERT_EQ(info.line_names.size(), 102u);
  EXPECT_EQ(gpio->find_line("LED17"), 17u);
  EXPECT_EQ(gpio->find_line("TRIGGER"), 100u);
  EXPECT_EQ(gpio->find_line("STROBE"), 101u);
  EXPECT_EQ(gpio->find_line("SR_DATA"), std::nullopt);
  // Bare paths and sim: URIs work as well.
  EXPECT_EQ(connect_sim_chip(socket_path.string())->find_line("LED3"), 3u);
  EXPECT_EQ(connect_sim_chip("sim:" + socket_path.string())->find_line("LED3"), 3u);
}

TEST_F(SimServerTest, SetsReachTheTimelineWithTheFirmwareStampsInOrder) {
  start();
  const auto gpio = connect_sim_chip(address);
  const std::vector<unsigned> offsets = {17, 18};
  const bool active_low[] = {false, false};
  auto lines = gpio->request_outputs(offsets, active_low, {}, "lightstage-domed");
  EXPECT_EQ(lines->size(), 2u);
  const std::vector<std::vector<int>> steps = {{1, 0}, {0, 1}, {0, 0}};
  std::int64_t t = 1'000;
  for (const auto& values : steps) lines->set(values, t += 1'000);
  EXPECT_EQ(gpio->info().consumers[17], "lightstage-domed");  // a round trip: every set before it is applied
  const auto timeline = chip->timeline();
  ASSERT_EQ(timeline.size(), 4u);
  EXPECT_EQ(timeline[0].line, "LED17");
  EXPECT_EQ(timeline[0].t_ns, 2'000);
  EXPECT_EQ(timeline[1].line, "LED17");
  EXPECT_EQ(timeline[1].value, 0);
  EXPECT_EQ(timeline[2].line, "LED18");
  EXPECT_EQ(timeline[2].t_ns, 3'000);
  EXPECT_EQ(timeline[3].t_ns, 4'000);
  EXPECT_THROW(lines->set(std::vector<int>{1}, 5'000), GpioError) << "one value per line";
}

TEST_F(SimServerTest, ABusyLineIsAGpioErrorNamingTheLineAndItsConsumer) {
  start();
  const auto firmware = connect_sim_chip(address);
  const auto intruder = connect_sim_chip(address);
  const std::vector<unsigned> led = {17};
  auto held = firmware->request_outputs(led, {}, {}, "lightstage-domed");
  const std::string error = gpio_error_of([&] { intruder->request_outputs(led, {}, {}, "other"); });
  EXPECT_NE(error.find("LED17"), std::string::npos) << error;
  EXPECT_NE(error.find("lightstage-domed"), std::string::npos) << error;
  EXPECT_NE(error.find(address), std::string::npos) << error;
  const std::vector<unsigned> missing = {130};
  EXPECT_NE(gpio_error_of([&] { firmware->request_outputs(missing, {}, {}, "x"); }).find("130"),
            std::string::npos);
  EXPECT_NE(gpio_error_of([&] { firmware->request_edges(130, false, "x"); }).find("130"), std::string::npos);
}

TEST_F(SimServerTest, LinesAreReleasedWithTheirHandleAndWithTheConnection) {
  start();
  const auto firmware = connect_sim_chip(address);
  const std::vector<unsigned> led = {17};
  {
    auto held = firmware->request_outputs(led, {}, {}, "first");
    EXPECT_EQ(firmware->info().consumers[17], "first");
  }
  EXPECT_EQ(firmware->info().consumers[17], "") << "released in order, before info";
  {
    const auto other = connect_sim_chip(address);
    auto held = other->request_outputs(led, {}, {}, "second");
    auto strobe = other->request_edges(101, false, "second");
  }  // `other` goes away without releasing: the sim frees its lines when it leaves
  const std::int64_t give_up = monotonic_now_ns() + 10'000 * kMs;
  while (firmware->info().consumers[17] != "" && monotonic_now_ns() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  EXPECT_EQ(firmware->info().consumers[17], "");
  EXPECT_EQ(firmware->info().consumers[101], "");
}

TEST_F(SimServerTest, ClosedLoopStrobeEdgesArriveStampedAndNotBeforeTheirTime) {
  start();
  const auto gpio = connect_sim_chip(address);
  const std::vector<unsigned> trigger_line = {100};
  auto trigger = gpio->request_outputs(trigger_line, {}, {}, "fw");
  auto strobe = gpio->request_edges(101, false, "fw");
  strobe->drain();
  const std::int64_t t0 = monotonic_now_ns();
  trigger->set(std::vector<int>{1}, t0);
  trigger->set(std::vector<int>{0}, t0 + 1'000);

  const auto start_edge = strobe->wait_until(t0 + 10'000 * kMs);
  ASSERT_TRUE(start_edge.has_value());
  EXPECT_GE(monotonic_now_ns(), start_edge->t_ns) << "sent when CLOCK_MONOTONIC reached it";
  EXPECT_TRUE(start_edge->rising);
  EXPECT_EQ(start_edge->offset, 101u);
  EXPECT_EQ(start_edge->t_ns, t0 + 2 * kMs);
  const auto end_edge = strobe->wait_until(t0 + 10'000 * kMs);
  ASSERT_TRUE(end_edge.has_value());
  EXPECT_GE(monotonic_now_ns(), end_edge->t_ns);
  EXPECT_FALSE(end_edge->rising);
  EXPECT_EQ(end_edge->t_ns, t0 + 7 * kMs);
  // Nothing more: the deadline passes with no edge.
  EXPECT_FALSE(strobe->wait_until(monotonic_now_ns() + 20 * kMs).has_value());

  const auto timeline = chip->timeline();
  const auto trig = entries_for(timeline, "TRIGGER");
  const auto strobes = entries_for(timeline, "STROBE");
  ASSERT_EQ(trig.size(), 2u);
  ASSERT_EQ(strobes.size(), 2u);
  EXPECT_LT(trig[0].t_ns, strobes[0].t_ns);
  EXPECT_LT(strobes[0].t_ns, strobes[1].t_ns);
}

TEST_F(SimServerTest, DrainDropsQueuedEdges) {
  start("sim-dome", 0, 1'000);
  const auto gpio = connect_sim_chip(address);
  const std::vector<unsigned> trigger_line = {100};
  auto trigger = gpio->request_outputs(trigger_line, {}, {}, "fw");
  auto strobe = gpio->request_edges(101, false, "fw");
  const std::int64_t t0 = monotonic_now_ns();
  trigger->set(std::vector<int>{1}, t0);
  ASSERT_TRUE(strobe->wait_until(t0 + 10'000 * kMs).has_value());
  ASSERT_TRUE(strobe->wait_until(t0 + 10'000 * kMs).has_value());
  trigger->set(std::vector<int>{0}, monotonic_now_ns());
  trigger->set(std::vector<int>{1}, monotonic_now_ns());
  // Wait until both edges of the second exposure are certainly queued, then drop them.
  const std::int64_t give_up = monotonic_now_ns() + 10'000 * kMs;
  while (entries_for(chip->timeline(), "STROBE").size() < 4 && monotonic_now_ns() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  gpio->info();  // edges are sent before the answer to a later request
  strobe->drain();
  EXPECT_FALSE(strobe->wait_until(monotonic_now_ns() + 20 * kMs).has_value());
}

// What a kernel queue gives a reader that wakes late: after catch_up() every edge already due is
// there to read at once, in order, however late the sim's strobe clock runs.
TEST_F(SimServerTest, CatchingUpBringsEveryEdgeAlreadyDue) {
  start();
  const auto gpio = connect_sim_chip(address);
  const std::vector<unsigned> trigger_line = {100};
  auto trigger = gpio->request_outputs(trigger_line, {}, {}, "fw");
  auto strobe = gpio->request_edges(101, false, "fw");
  for (int round = 0; round < 20; ++round) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));  // past the last round's exposure
    const std::int64_t t0 = monotonic_now_ns() - 50 * kMs;       // this one ended 43 ms ago
    trigger->set(std::vector<int>{1}, t0);
    trigger->set(std::vector<int>{0}, t0 + 1'000);
    strobe->catch_up();
    const auto rise = strobe->wait_until(0);
    const auto fall = strobe->wait_until(0);
    ASSERT_TRUE(rise && fall) << "round " << round;
    EXPECT_TRUE(rise->rising);
    EXPECT_EQ(rise->t_ns, t0 + 2 * kMs);
    EXPECT_FALSE(fall->rising);
    EXPECT_EQ(fall->t_ns, t0 + 7 * kMs);
    strobe->catch_up();
    EXPECT_FALSE(strobe->wait_until(0).has_value());
  }
}

TEST_F(SimServerTest, ARunTimeLoseStrobeFaultLeavesTheWaitEmpty) {
  start();
  inject_sim_fault(address, "lose-strobe:1");
  const auto gpio = connect_sim_chip(address);
  const std::vector<unsigned> trigger_line = {100};
  auto trigger = gpio->request_outputs(trigger_line, {}, {}, "fw");
  auto strobe = gpio->request_edges(101, false, "fw");
  const std::int64_t t0 = monotonic_now_ns();
  trigger->set(std::vector<int>{1}, t0);
  EXPECT_FALSE(strobe->wait_until(t0 + 200 * kMs).has_value());
  EXPECT_EQ(chip->stats().strobes_lost, 1);
  trigger->set(std::vector<int>{0}, t0 + 300 * kMs);
  trigger->set(std::vector<int>{1}, t0 + 301 * kMs);  // the second trigger is served
  EXPECT_TRUE(strobe->wait_until(monotonic_now_ns() + 10'000 * kMs).has_value());
}

TEST_F(SimServerTest, ABadFaultIsAnErrorFromTheSim) {
  start();
  const std::string error = gpio_error_of([&] { inject_sim_fault(address, "stuck:NOPE"); });
  EXPECT_NE(error.find("NOPE"), std::string::npos) << error;
  EXPECT_NE(gpio_error_of([&] { inject_sim_fault(address, "melt:1"); }).find("melt"), std::string::npos);
}

TEST_F(SimServerTest, DropConnectionClosesAfterNMessagesAndCallsThenFail) {
  start();
  const auto gpio = connect_sim_chip(address);
  inject_sim_fault(address, "drop-connection:3");
  const std::vector<unsigned> led = {5};
  auto lines = gpio->request_outputs(led, {}, {}, "fw");  // 1
  lines->set(std::vector<int>{1}, 10);                    // 2
  lines->set(std::vector<int>{0}, 20);                    // 3: answered, then the sim hangs up
  const std::string error = gpio_error_of([&] { gpio->info(); });
  EXPECT_NE(error.find("connection lost"), std::string::npos) << error;
  EXPECT_NE(error.find(address), std::string::npos) << error;
  EXPECT_THROW(lines->set(std::vector<int>{1}, 30), GpioError) << "every later call fails";
  // The fault fired once: a new connection is served normally, and the line was released.
  const auto again = connect_sim_chip(address);
  EXPECT_NO_THROW(again->request_outputs(led, {}, {}, "fw"));
  EXPECT_EQ(entries_for(chip->timeline(), "LED5").size(), 2u);
}

TEST_F(SimServerTest, ARunTimeStuckLineIgnoresTheClient) {
  start();
  inject_sim_fault(address, "stuck:LED9");
  const auto gpio = connect_sim_chip(address);
  const std::vector<unsigned> led = {9};
  auto lines = gpio->request_outputs(led, {}, {}, "fw");
  lines->set(std::vector<int>{1}, 10);
  gpio->info();
  EXPECT_FALSE(chip->led_lit(9));
}

TEST_F(SimServerTest, ADamagedMessageIsAnsweredWithAnErrorAndServingGoesOn) {
  start();
  MessageChannel raw(connect_socket_link(address, std::chrono::milliseconds(2000)));
  const std::vector<std::uint8_t> garbage = {0xff, 0xff, 0xff, 0xff, 0x0f};
  raw.link().write(protocol::encode_frame(garbage));
  proto::sim::ServerMessage reply;
  ASSERT_TRUE(raw.receive(reply, std::chrono::milliseconds(10'000)));
  EXPECT_TRUE(reply.has_error());
  proto::sim::ClientMessage empty;
  empty.set_request_id(7);
  raw.send(empty);
  ASSERT_TRUE(raw.receive(reply, std::chrono::milliseconds(10'000)));
  EXPECT_EQ(reply.request_id(), 7u);
  EXPECT_TRUE(reply.has_error());
  proto::sim::ClientMessage info;
  info.set_request_id(8);
  info.mutable_chip_info();
  raw.send(info);
  ASSERT_TRUE(raw.receive(reply, std::chrono::milliseconds(10'000)));
  EXPECT_EQ(reply.request_id(), 8u);
  EXPECT_TRUE(reply.has_chip_info());
}

TEST_F(SimServerTest, StoppingRemovesTheSocketAndClientsSeeGpioErrors) {
  start();
  const auto gpio = connect_sim_chip(address);
  EXPECT_TRUE(std::filesystem::exists(socket_path));
  host.stop();
  EXPECT_FALSE(std::filesystem::exists(socket_path));
  EXPECT_THROW(gpio->info(), GpioError);
  EXPECT_THROW(connect_sim_chip(address, std::chrono::milliseconds(0)), GpioError);
}

TEST_F(SimServerTest, ChainRigOverTheSocket) {
  start("matrix-64");
  const auto gpio = connect_sim_chip(address);
  std::vector<unsigned> offsets;
  for (const char* name : {"SR_DATA", "SR_CLK", "SR_LATCH", "SR_OE"}) {
    const auto offset = gpio->find_line(name);
    ASSERT_TRUE(offset.has_value()) << name;
    offsets.push_back(*offset);
  }
  const bool active_low[] = {false, false, false, true};
  auto lines = gpio->request_outputs(offsets, active_low, {}, "fw");
  std::vector<bool> bits(64, false);
  bits[33] = true;
  const std::int64_t latched = testing::write_chain(
      [&](const std::vector<int>& values, std::int64_t t_ns) { lines->set(values, t_ns); }, bits, 1'000);
  gpio->info();
  const auto lit = testing::led_entries(chip->timeline());
  ASSERT_EQ(lit.size(), 1u);
  EXPECT_EQ(lit[0].line, "LED33");
  EXPECT_EQ(lit[0].via, "leds");
  EXPECT_EQ(lit[0].t_ns, latched - 10);
}

TEST_F(SimServerTest, ManyPipelinedSetsArriveCompleteAndInOrder) {
  start();
  const auto gpio = connect_sim_chip(address);
  std::vector<unsigned> offsets(96);
  for (unsigned i = 0; i < 96; ++i) offsets[i] = i;
  auto leds = gpio->request_outputs(offsets, {}, {}, "fw");
  constexpr int kSets = 4000;
  std::vector<int> values(96, 0);
  const std::int64_t begin = monotonic_now_ns();
  for (int i = 0; i < kSets; ++i) {
    // One LED on, the previous one off: exactly two changes per set after the first.
    std::fill(values.begin(), values.end(), 0);
    values[static_cast<std::size_t>(i % 96)] = 1;
    leds->set(values, 1'000 + i);
  }
  gpio->info();
  const std::int64_t sets_done = monotonic_now_ns();
  constexpr int kCalls = 200;
  for (int i = 0; i < kCalls; ++i) gpio->info();
  const std::int64_t calls_done = monotonic_now_ns();

  const auto timeline = chip->timeline();
  ASSERT_EQ(timeline.size(), static_cast<std::size_t>(2 * kSets - 1));
  for (std::size_t i = 1; i < timeline.size(); ++i) ASSERT_LE(timeline[i - 1].t_ns, timeline[i].t_ns) << i;
  std::printf(
      "[ measured ] %d pipelined sets of 96 lines applied in %.1f ms (%.0f sets/s); "
      "info() round trip %.0f us on average\n",
      kSets, (sets_done - begin) / 1e6, kSets / ((sets_done - begin) / 1e9),
      (calls_done - sets_done) / 1e3 / kCalls);
}

TEST_F(SimServerTest, StrobeEdgesAreDeliveredInOrderForEveryExposure) {
  start("sim-dome", 200'000, 1'000'000);
  const auto gpio = connect_sim_chip(address);
  const std::vector<unsigned> trigger_line = {100};
  auto trigger = gpio->request_outputs(trigger_line, {}, {}, "fw");
  auto strobe = gpio->request_edges(101, false, "fw");
  std::vector<std::int64_t> late_ns;
  for (int i = 0; i < 20; ++i) {
    strobe->drain();
    const std::int64_t t0 = monotonic_now_ns();
    trigger->set(std::vector<int>{1}, t0);
    trigger->set(std::vector<int>{0}, t0 + 50'000);
    for (const bool rising : {true, false}) {
      const auto edge = strobe->wait_until(t0 + 10'000 * kMs);
      ASSERT_TRUE(edge.has_value());
      const std::int64_t received = monotonic_now_ns();
      EXPECT_EQ(edge->rising, rising);
      EXPECT_EQ(edge->t_ns, t0 + (rising ? 200'000 : 1'200'000));
      EXPECT_GE(received, edge->t_ns);
      late_ns.push_back(received - edge->t_ns);
    }
  }
  std::sort(late_ns.begin(), late_ns.end());
  std::printf("[ measured ] strobe edge received after its time: median %.0f us, max %.0f us (%zu edges)\n",
              late_ns[late_ns.size() / 2] / 1e3, late_ns.back() / 1e3, late_ns.size());
}

}  // namespace
}  // namespace lightstage::sim::gpio
