#include "lightstage/firmware/controller_server.hpp"

#include "lightstage/common/clock.hpp"
#include "lightstage/common/framing.hpp"
#include "lightstage/common/socket_link.hpp"
#include "lightstage/testing/paths.hpp"

#include "support/fake_chip.hpp"
#include "support/sequence_builder.hpp"
#include "support/test_host.hpp"
#include "support/test_rigs.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <thread>

namespace lightstage::firmware {
namespace {

using testing::FakeChip;
using ::testing::HasSubstr;
using testing::TestHost;
using namespace std::chrono_literals;

constexpr std::int64_t kUs = 1000;

proto::HostMessage set_leds(std::initializer_list<int> ids, float level = 1.0F) {
  proto::HostMessage message;
  for (const int id : ids) {
    proto::LedLevel& led = *message.mutable_set_leds()->add_leds();
    led.set_led_id(static_cast<std::uint32_t>(id));
    led.set_level(level);
  }
  if (ids.size() == 0) message.mutable_set_leds();
  return message;
}

proto::HostMessage upload(const proto::Sequence& sequence) {
  proto::HostMessage message;
  *message.mutable_upload()->mutable_sequence() = sequence;
  return message;
}

proto::HostMessage run(std::uint32_t id) {
  proto::HostMessage message;
  message.mutable_run()->set_sequence_id(id);
  return message;
}

proto::HostMessage status() {
  proto::HostMessage message;
  message.mutable_status();
  return message;
}

proto::Error::Code error_code(const proto::ControllerMessage& reply) {
  EXPECT_TRUE(reply.has_error()) << reply.ShortDebugString();
  return reply.error().code();
}

bool is_done(const proto::ControllerMessage& message) { return message.has_sequence_done(); }

// A controller for the direct rig (2 s on-time) on a fake chip with a camera,
// real time, served to one in-process host over a socket pair.
struct ServerBench {
  explicit ServerBench(testing::FakeCamera camera = {8, 9, 50 * kUs, 2000 * kUs, false},
                       ServerOptions options = {.gpio_uri = "fake:chip"})
      : rig(testing::direct_rig(2'000'000, 0.5, 10'000'000)), chip(FakeChip::with_lines(16, clock)) {
    chip->set_camera(camera);
    controller = std::make_unique<Controller>(rig, open_dome_io(rig, *chip, clock), clock);
    server = std::make_unique<ControllerServer>(*controller, options);
    auto [host_end, controller_end] = socket_link_pair();
    thread = std::thread(
        [this, link = std::move(controller_end)]() mutable { server->serve_client(std::move(link), stop); });
    host = std::make_unique<TestHost>(std::move(host_end));
  }
  ~ServerBench() {
    stop = true;
    if (thread.joinable()) thread.join();
  }

  bool dark() const {
    for (unsigned line = 0; line < 4; ++line) {
      if (chip->value(line) != 0) return false;
    }
    return true;
  }

  MonotonicClock clock;
  Rig rig;
  std::unique_ptr<FakeChip> chip;
  std::unique_ptr<Controller> controller;
  std::unique_ptr<ControllerServer> server;
  std::atomic<bool> stop{false};
  std::thread thread;
  std::unique_ptr<TestHost> host;
};

TEST(ControllerServer, RefusesCommandsBeforeHelloThenAnswersHelloWithInfo) {
  ServerBench bench;
  EXPECT_EQ(error_code(bench.host->request(status())), proto::Error::NOT_NEGOTIATED);
  EXPECT_EQ(error_code(bench.host->request(set_leds({1}))), proto::Error::NOT_NEGOTIATED);
  EXPECT_EQ(bench.chip->value(1), 0);

  const proto::ControllerMessage reply = bench.host->hello();
  ASSERT_TRUE(reply.has_info()) << reply.ShortDebugString();
  const proto::Info& info = reply.info();
  EXPECT_EQ(info.protocol_version(), kProtocolVersion);
  EXPECT_EQ(info.rig_name(), "direct-4");
  EXPECT_EQ(info.led_count(), 4u);
  ASSERT_EQ(info.leds_size(), 4);
  EXPECT_FLOAT_EQ(info.leds(0).max_on_us(), 2'000'000.0F);
  EXPECT_TRUE(info.capabilities().strobe_input());
  EXPECT_FALSE(info.capabilities().dimming());
  EXPECT_EQ(info.capabilities().watchdog_timeout_ms(), 1000u);
  EXPECT_EQ(info.gpio_uri(), "fake:chip");
  EXPECT_GT(info.clock_ns(), 0);
  EXPECT_TRUE(bench.host->request(status()).has_status());
}

TEST(ControllerServer, RejectsAHostWhoseVersionsDoNotOverlap) {
  ServerBench bench;
  const proto::ControllerMessage reply = bench.host->hello(0, /*version=*/9, /*min_version=*/5);
  EXPECT_EQ(error_code(reply), proto::Error::VERSION_MISMATCH);
  EXPECT_THAT(reply.error().message(), HasSubstr("5..9"));
  EXPECT_EQ(error_code(bench.host->request(status())), proto::Error::NOT_NEGOTIATED);
  // A range that reaches down to ours negotiates our version.
  EXPECT_EQ(bench.host->hello(0, 4, 1).info().protocol_version(), kProtocolVersion);
}

TEST(ControllerServer, AnswersMalformedFramesWithErrorsAndKeepsServing) {
  ServerBench bench;
  ASSERT_TRUE(bench.host->hello().has_info());
  const auto malformed = [](const proto::ControllerMessage& m) {
    return m.has_error() && m.error().code() == proto::Error::MALFORMED_FRAME;
  };
  // Garbage between frames.
  const std::string garbage = "this is not a frame";
  bench.host->send_raw(std::span(reinterpret_cast<const std::uint8_t*>(garbage.data()), garbage.size()));
  ASSERT_TRUE(bench.host->wait_for(malformed)) << "garbage";
  // A damaged frame (bad CRC).
  std::string bytes;
  status().SerializeToString(&bytes);
  auto frame =
      protocol::encode_frame(std::span(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()));
  frame.back() ^= 0xFF;
  bench.host->send_raw(frame);
  // A sound frame whose payload is no HostMessage.
  const std::vector<std::uint8_t> not_protobuf = {0xFF, 0xFF, 0xFF, 0xFF, 0x07};
  bench.host->send_raw(protocol::encode_frame(not_protobuf));
  // Still serving: the next request gets its reply.
  EXPECT_TRUE(bench.host->request(status()).has_status());
  const auto& seen = bench.host->unsolicited();
  EXPECT_GE(std::count_if(seen.begin(), seen.end(), malformed), 3);
}

TEST(ControllerServer, SetsStaticLedsWithinTheRules) {
  ServerBench bench;
  ASSERT_TRUE(bench.host->hello().has_info());
  EXPECT_TRUE(bench.host->request(set_leds({1, 3})).has_ack());
  EXPECT_EQ(bench.chip->value(1), 1);
  EXPECT_EQ(bench.chip->value(3), 1);
  EXPECT_THAT(bench.host->request(status()).status().leds_on(), ::testing::UnorderedElementsAre(1u, 3u));
  EXPECT_TRUE(bench.host->request(set_leds({})).has_ack());
  EXPECT_TRUE(bench.dark());
  EXPECT_EQ(error_code(bench.host->request(set_leds({9}))), proto::Error::BAD_REQUEST);
  EXPECT_EQ(error_code(bench.host->request(set_leds({2}, 0.5F))), proto::Error::BAD_REQUEST);
  proto::HostMessage empty;
  EXPECT_EQ(error_code(bench.host->request(empty)), proto::Error::BAD_REQUEST);
}

TEST(ControllerServer, RunsAnUploadedSequenceAckFirstThenStepsThenDone) {
  ServerBench bench;
  ASSERT_TRUE(bench.host->hello().has_info());
  const proto::Sequence sequence = testing::one_led_per_step(
      3, {0, 1, 2, 3}, {.leds = {}, .settle_us = 100, .exposure_us = 1000, .gap_us = 500});
  EXPECT_TRUE(bench.host->request(upload(sequence)).has_ack());
  EXPECT_TRUE(bench.host->request(run(3)).has_ack());
  for (const auto& message : bench.host->unsolicited()) {
    EXPECT_FALSE(message.has_step_event()) << "a step event arrived before the Ack";
  }
  const auto done = bench.host->wait_for(is_done);
  ASSERT_TRUE(done);
  EXPECT_EQ(done->sequence_done().outcome(), proto::OK) << done->sequence_done().detail();
  EXPECT_EQ(done->sequence_done().steps_run(), 4u);
  std::vector<proto::StepEvent> events;
  for (const auto& message : bench.host->unsolicited()) {
    if (message.has_step_event()) events.push_back(message.step_event());
  }
  ASSERT_EQ(events.size(), 4u);
  for (std::uint32_t i = 0; i < 4; ++i) {
    EXPECT_EQ(events[i].step(), i);
    EXPECT_LT(events[i].leds_on_ns(), events[i].trigger_ns());
    EXPECT_GE(events[i].leds_off_ns() - events[i].trigger_ns(), 1000 * kUs);
    EXPECT_GE(events[i].lateness_ns(), 0);
  }
  EXPECT_TRUE(bench.dark());
}

TEST(ControllerServer, ClosedLoopStepEndsAtTheStrobe) {
  ServerBench bench;
  ASSERT_TRUE(bench.host->hello().has_info());
  const proto::Sequence sequence = testing::make_sequence(
      4,
      {{.leds = {2}, .settle_us = 100, .exposure_us = 0, .wait_strobe = true, .strobe_timeout_us = 500'000}});
  ASSERT_TRUE(bench.host->request(upload(sequence)).has_ack());
  ASSERT_TRUE(bench.host->request(run(4)).has_ack());
  const auto step = bench.host->wait_for([](const auto& m) { return m.has_step_event(); });
  ASSERT_TRUE(step);
  const proto::StepEvent& event = step->step_event();
  EXPECT_EQ(event.outcome(), proto::OK) << event.detail();
  EXPECT_GT(event.strobe_rise_ns(), event.trigger_ns());
  EXPECT_GT(event.strobe_fall_ns(), event.strobe_rise_ns());
  EXPECT_GE(event.leds_off_ns(), event.strobe_fall_ns());
}

TEST(ControllerServer, RefusesSequencesBeyondTheLimitsAndUnknownIds) {
  ServerBench bench;
  ASSERT_TRUE(bench.host->hello().has_info());
  const auto reply =
      bench.host->request(upload(testing::make_sequence(5, {{.leds = {1}, .exposure_us = 3'000'000}})));
  EXPECT_EQ(error_code(reply), proto::Error::SAFETY_LIMIT);
  EXPECT_THAT(reply.error().message(), HasSubstr("max_on_us"));
  EXPECT_EQ(error_code(bench.host->request(run(5))), proto::Error::NO_SUCH_SEQUENCE);
}

TEST(ControllerServer, IsBusyWhileASequenceRunsUntilAborted) {
  ServerBench bench;
  ASSERT_TRUE(bench.host->hello(5000).has_info());
  ASSERT_TRUE(
      bench.host->request(upload(testing::make_sequence(6, {{.leds = {0}, .exposure_us = 1'500'000}})))
          .has_ack());
  ASSERT_TRUE(bench.host->request(run(6)).has_ack());
  EXPECT_EQ(error_code(bench.host->request(run(6))), proto::Error::BUSY);
  EXPECT_EQ(error_code(bench.host->request(set_leds({1}))), proto::Error::BUSY);
  EXPECT_EQ(bench.host->request(status()).status().state(), proto::Status::RUNNING);
  proto::HostMessage abort;
  abort.mutable_abort();
  EXPECT_TRUE(bench.host->request(abort).has_ack());
  const auto done = bench.host->wait_for(is_done);
  ASSERT_TRUE(done);
  EXPECT_EQ(done->sequence_done().outcome(), proto::ABORTED_BY_HOST);
  EXPECT_TRUE(bench.dark());
}

TEST(ControllerServer, WatchdogDarkensStaticLedsWhenTheHostFallsSilent) {
  ServerBench bench;
  ASSERT_EQ(bench.host->hello(100).info().capabilities().watchdog_timeout_ms(), 100u);
  ASSERT_TRUE(bench.host->request(set_leds({0, 2})).has_ack());
  const auto fault = bench.host->wait_for([](const auto& m) { return m.has_fault(); });
  ASSERT_TRUE(fault);
  EXPECT_EQ(fault->fault().outcome(), proto::WATCHDOG);
  EXPECT_THAT(fault->fault().detail(), HasSubstr("watchdog"));
  EXPECT_TRUE(bench.dark());
  const proto::Status state = bench.host->request(status()).status();
  EXPECT_EQ(state.state(), proto::Status::FAULT);
  EXPECT_THAT(state.last_fault(), HasSubstr("watchdog"));
}

TEST(ControllerServer, WatchdogAbortsARunningSequence) {
  ServerBench bench;
  ASSERT_TRUE(bench.host->hello(100).has_info());
  ASSERT_TRUE(
      bench.host->request(upload(testing::make_sequence(7, {{.leds = {3}, .exposure_us = 1'800'000}})))
          .has_ack());
  ASSERT_TRUE(bench.host->request(run(7)).has_ack());
  const auto done = bench.host->wait_for(is_done);
  ASSERT_TRUE(done);
  EXPECT_EQ(done->sequence_done().outcome(), proto::WATCHDOG);
  EXPECT_TRUE(bench.dark());
}

TEST(ControllerServer, HeartbeatsKeepTheWatchdogQuiet) {
  ServerBench bench;
  ASSERT_TRUE(bench.host->hello(400).has_info());
  ASSERT_TRUE(bench.host->request(set_leds({1})).has_ack());
  proto::HostMessage beat;
  beat.mutable_heartbeat()->set_counter(1);
  const auto until = std::chrono::steady_clock::now() + 800ms;
  while (std::chrono::steady_clock::now() < until) {
    bench.host->send(beat);  // request_id 0: no reply
    std::this_thread::sleep_for(20ms);
  }
  EXPECT_EQ(bench.chip->value(1), 1);
  EXPECT_TRUE(bench.host->request(beat).has_ack()) << "a heartbeat with an id is acknowledged";
  for (const auto& message : bench.host->unsolicited())
    EXPECT_FALSE(message.has_fault()) << message.ShortDebugString();
}

TEST(ControllerServer, DarkensTheDomeWhenTheLinkIsLost) {
  ServerBench bench;
  ASSERT_TRUE(bench.host->hello(60'000).has_info());
  ASSERT_TRUE(bench.host->request(set_leds({3})).has_ack());
  bench.host->channel().link().shutdown();
  bench.thread.join();  // serve_client returns once the link is gone
  EXPECT_TRUE(bench.dark());
}

TEST(ControllerServer, RefusesASecondHostWithBusy) {
  MonotonicClock clock;
  const Rig rig = testing::direct_rig(2'000'000, 0.5, 10'000'000);
  auto chip = FakeChip::with_lines(16, clock);
  Controller controller(rig, open_dome_io(rig, *chip, clock), clock);
  ControllerServer server(controller, {});
  const std::string uri = "unix:" + (lightstage::testing::scratch_dir() / "domed.sock").string();
  auto listener = listen_socket_link(uri);
  std::atomic<bool> stop{false};
  std::thread serving([&] { server.serve(*listener, stop); });

  TestHost first(connect_socket_link(uri, 5s));
  ASSERT_TRUE(first.hello().has_info());
  MessageChannel second(connect_socket_link(uri, 5s));
  proto::ControllerMessage refusal;
  ASSERT_TRUE(second.receive(refusal, 10s));
  EXPECT_EQ(error_code(refusal), proto::Error::BUSY);
  EXPECT_THROW(
      {
        proto::ControllerMessage more;
        while (true) second.receive(more, 10s);
      },
      LinkClosed);
  EXPECT_TRUE(first.request(status()).has_status()) << "the first host keeps control";

  ASSERT_TRUE(first.request(set_leds({2})).has_ack());
  stop = true;  // like SIGTERM
  serving.join();
  EXPECT_EQ(chip->value(2), 0);
}

constexpr testing::FakeCamera kCamera{8, 9, 50 * kUs, 2000 * kUs, false};

bool is_error(const proto::ControllerMessage& message, proto::Error::Code code) {
  return message.has_error() && message.error().code() == code;
}

// Reads until the server hangs up; the Error{code} must come before that.
void expect_hang_up_with(TestHost& host, proto::Error::Code code, std::chrono::milliseconds within) {
  bool told = false;
  const auto deadline = std::chrono::steady_clock::now() + within;
  try {
    while (std::chrono::steady_clock::now() < deadline) {
      proto::ControllerMessage message;
      if (host.channel().receive(message, 20ms)) told = told || is_error(message, code);
    }
    ADD_FAILURE() << "still connected after " << within.count() << " ms";
  } catch (const LinkClosed&) {
  }
  EXPECT_TRUE(told) << "hung up without saying " << proto::Error::Code_Name(code);
}

TEST(ControllerServer, HangsUpOnAConnectionThatNeverSaysHello) {
  ServerBench bench(kCamera, {.gpio_uri = "fake:chip", .hello_timeout = 200ms});
  const auto start = std::chrono::steady_clock::now();
  const std::uint8_t half_a_header[] = {'L', 'S', 0x10};
  bench.host->send_raw(half_a_header);
  expect_hang_up_with(*bench.host, proto::Error::SESSION_EXPIRED, 5s);
  EXPECT_GE(std::chrono::steady_clock::now() - start, 200ms);
  bench.thread.join();  // serve_client returned: the lock is free
}

// A link on which nothing arrives and for which nobody waits (a serial line
// with no host on it) is not hung up on: the first host to talk is served.
TEST(ControllerServer, ASilentLinkThatKeepsNobodyOutStaysOpen) {
  ServerBench bench(kCamera, {.gpio_uri = "fake:chip", .hello_timeout = 100ms});
  std::this_thread::sleep_for(400ms);
  EXPECT_TRUE(bench.host->hello().has_info());
}

// A peer trickling bytes that never make a frame proves nothing: after Hello
// it loses its lease (and the dome goes dark), before Hello its hello timeout runs.
TEST(ControllerServer, ASlowlorisHostLosesItsLeaseAndTheDomeGoesDark) {
  ServerBench bench(kCamera, {.gpio_uri = "fake:chip", .hello_timeout = 60s, .idle_lease = 300ms});
  ASSERT_TRUE(bench.host->hello(100).has_info());
  ASSERT_TRUE(bench.host->request(set_leds({1})).has_ack());
  std::atomic<bool> trickling{true};
  std::thread trickle([&] {
    const std::uint8_t header[] = {'L', 'S', 0x00, 0x10, 0x00, 0x00};
    try {
      for (std::size_t i = 0; trickling; ++i) {
        bench.host->send_raw(std::span(header).subspan(i % sizeof(header), 1));
        std::this_thread::sleep_for(10ms);
      }
    } catch (const LinkClosed&) {
    }
  });
  expect_hang_up_with(*bench.host, proto::Error::SESSION_EXPIRED, 5s);
  trickling = false;
  trickle.join();
  bench.thread.join();
  EXPECT_TRUE(bench.dark());
}

// Only valid messages prove the host alive: garbage, however steady, lets
// the watchdog fire.
TEST(ControllerServer, GarbageDoesNotFeedTheWatchdog) {
  ServerBench bench;
  ASSERT_TRUE(bench.host->hello(200).has_info());
  ASSERT_TRUE(bench.host->request(set_leds({0})).has_ack());
  const std::string garbage = "xx";
  const auto until = std::chrono::steady_clock::now() + 800ms;
  while (std::chrono::steady_clock::now() < until) {
    bench.host->send_raw(std::span(reinterpret_cast<const std::uint8_t*>(garbage.data()), garbage.size()));
    std::this_thread::sleep_for(10ms);
  }
  const auto fault = bench.host->wait_for([](const auto& m) { return m.has_fault(); }, 2s);
  ASSERT_TRUE(fault) << "garbage kept the watchdog fed";
  EXPECT_EQ(fault->fault().outcome(), proto::WATCHDOG);
  EXPECT_TRUE(bench.dark());
}

// Empty messages (valid frames, no request) arriving back to back neither
// feed the watchdog nor keep it from being checked.
TEST(ControllerServer, AFloodOfEmptyMessagesDoesNotFeedTheWatchdog) {
  ServerBench bench;
  ASSERT_TRUE(bench.host->hello(200).has_info());
  ASSERT_TRUE(bench.host->request(set_leds({3})).has_ack());
  std::atomic<bool> flooding{true};
  std::thread flood([&] {
    const proto::HostMessage empty;
    const auto until = std::chrono::steady_clock::now() + 600ms;
    while (std::chrono::steady_clock::now() < until) bench.host->send(empty);
    flooding = false;
  });
  // Read every reply as it comes, so that neither side's buffer fills; then
  // until the server has nothing more to say.
  std::optional<proto::Fault> fault;
  proto::ControllerMessage message;
  const auto note = [&] {
    if (message.has_fault() && !fault) fault = message.fault();
  };
  while (flooding) {
    if (bench.host->channel().receive(message, 20ms)) note();
  }
  while (bench.host->channel().receive(message, 300ms)) note();
  flood.join();
  ASSERT_TRUE(fault) << "empty messages kept the watchdog fed";
  EXPECT_EQ(fault->outcome(), proto::WATCHDOG);
  EXPECT_TRUE(bench.dark());
}

TEST(ControllerServer, DropsTheSequencesOfAHostWhenItsSessionEnds) {
  MonotonicClock clock;
  const Rig rig = testing::direct_rig(2'000'000, 0.5, 10'000'000);
  auto chip = FakeChip::with_lines(16, clock);
  Controller controller(rig, open_dome_io(rig, *chip, clock), clock);
  ControllerServer server(controller, {});
  std::atomic<bool> stop{false};
  const auto session = [&](const std::function<void(TestHost&)>& talk) {
    auto [host_end, controller_end] = socket_link_pair();
    std::thread serving(
        [&, link = std::move(controller_end)]() mutable { server.serve_client(std::move(link), stop); });
    {
      TestHost host(std::move(host_end));
      ASSERT_TRUE(host.hello().has_info());
      talk(host);
    }  // hangs up
    serving.join();
  };
  session([](TestHost& host) {
    ASSERT_TRUE(host.request(upload(testing::one_led_per_step(8, {1}, {}))).has_ack());
  });
  session(
      [](TestHost& host) { EXPECT_EQ(error_code(host.request(run(8))), proto::Error::NO_SUCH_SEQUENCE); });
}

// After the GPIO backend fails the server stops serving (the daemon then
// exits non-zero); the host hears why first.
TEST(ControllerServer, StopsServingWhenTheGpioBackendFails) {
  ServerBench bench;
  ASSERT_TRUE(bench.host->hello().has_info());
  bench.chip->fail_after_sets(0);
  EXPECT_EQ(error_code(bench.host->request(set_leds({2}))), proto::Error::GPIO_ERROR);
  bench.thread.join();  // returns without a stop request
  EXPECT_THAT(bench.controller->status().last_fault(), HasSubstr("GPIO backend lost"));
  EXPECT_EQ(bench.controller->status().state(), proto::Status::FAULT);
  const auto fault = bench.host->wait_for([](const auto& m) { return m.has_fault(); }, 2s);
  ASSERT_TRUE(fault);
  EXPECT_EQ(fault->fault().outcome(), proto::GPIO_ERROR);
}

// BUSY says who holds the dome and since when; a holder that never says
// Hello gives the lock up at its hello timeout.
TEST(ControllerServer, BusyNamesTheHolderAndAnIdleHolderLosesTheLock) {
  MonotonicClock clock;
  const Rig rig = testing::direct_rig(2'000'000, 0.5, 10'000'000);
  auto chip = FakeChip::with_lines(16, clock);
  Controller controller(rig, open_dome_io(rig, *chip, clock), clock);
  ControllerServer server(controller, {.gpio_uri = "", .hello_timeout = 500ms});
  const std::string uri = "unix:" + (lightstage::testing::socket_dir() / "idle.sock").string();
  auto listener = listen_socket_link(uri);
  std::atomic<bool> stop{false};
  std::thread serving([&] { server.serve(*listener, stop); });

  MessageChannel idle(connect_socket_link(uri, 5s));  // connects, says nothing
  std::this_thread::sleep_for(100ms);
  {
    MessageChannel second(connect_socket_link(uri, 5s));
    proto::ControllerMessage refusal;
    ASSERT_TRUE(second.receive(refusal, 10s));
    EXPECT_EQ(error_code(refusal), proto::Error::BUSY);
    EXPECT_THAT(refusal.error().message(), HasSubstr("connected since 20"));
    EXPECT_THAT(refusal.error().message(), HasSubstr("ms ago"));
    EXPECT_THAT(refusal.error().message(), HasSubstr("no Hello yet"));
    EXPECT_THAT(refusal.error().message(), HasSubstr("unix:"));
  }
  // After the idle holder's hello timeout, the next host gets the dome.
  std::this_thread::sleep_for(600ms);
  TestHost next(connect_socket_link(uri, 5s));
  EXPECT_TRUE(next.hello().has_info());
  stop = true;
  serving.join();
}

}  // namespace
}  // namespace lightstage::firmware
