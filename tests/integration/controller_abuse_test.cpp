// Protocol abuse against the real lightstage-domed over the simulated dome:
// a holder that never says Hello, a slowloris, frames cut short, garbage
// meant to keep the watchdog fed, and a flood. Whatever a peer does, the
// dome ends dark and the next host gets served. Checks are on what the
// daemon answers and on the sim's recorded timeline, with generous bounds.
#include "dome_fixture.hpp"

#include "lightstage/common/clock.hpp"
#include "lightstage/common/framing.hpp"
#include "lightstage/common/message_channel.hpp"
#include "lightstage/common/socket_link.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <limits>
#include <string>
#include <thread>

namespace lightstage::testing {
namespace {

using namespace std::chrono_literals;
using Bytes = std::vector<std::uint8_t>;
constexpr std::int64_t kNever = std::numeric_limits<std::int64_t>::max();

// A host end that speaks the protocol by hand, to misbehave exactly.
class RawHost {
 public:
  explicit RawHost(const SimulatedDome& dome) : channel_(connect_socket_link(dome.controller_uri(), 5s)) {}

  // Sends `message` with a fresh request id; the reply to it (unsolicited
  // messages and error reports in between are skipped), or nullopt after `timeout`.
  std::optional<proto::ControllerMessage> request(proto::HostMessage message,
                                                  std::chrono::milliseconds timeout = 3s) {
    message.set_request_id(++last_id_);
    channel_.send(message);
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      proto::ControllerMessage reply;
      try {
        if (!channel_.receive(reply, 20ms)) continue;
      } catch (const ProtocolError&) {
        continue;
      }
      if (reply.request_id() == last_id_) return reply;
      seen_.push_back(reply);
    }
    return std::nullopt;
  }

  std::optional<proto::ControllerMessage> hello(std::uint32_t watchdog_ms = 0) {
    proto::HostMessage message;
    message.mutable_hello()->set_protocol_version(kProtocolVersion);
    message.mutable_hello()->set_min_protocol_version(kProtocolVersion);
    message.mutable_hello()->set_client("abuse test");
    message.mutable_hello()->set_watchdog_timeout_ms(watchdog_ms);
    return request(message);
  }

  std::optional<proto::ControllerMessage> set_led(std::uint32_t id) {
    proto::HostMessage message;
    proto::LedLevel& led = *message.mutable_set_leds()->add_leds();
    led.set_led_id(id);
    led.set_level(1.0F);
    return request(message);
  }

  void write(const Bytes& bytes) { channel_.link().write(bytes); }

  // Reads until the daemon hangs up (true) or `timeout` passes (false);
  // keeps what it said.
  bool wait_for_hang_up(std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    try {
      while (std::chrono::steady_clock::now() < deadline) {
        proto::ControllerMessage message;
        try {
          if (channel_.receive(message, 20ms)) seen_.push_back(message);
        } catch (const ProtocolError&) {
        }
      }
    } catch (const LinkClosed&) {
      return true;
    }
    return false;
  }

  bool saw_error(proto::Error::Code code) const {
    for (const auto& message : seen_) {
      if (message.has_error() && message.error().code() == code) return true;
    }
    return false;
  }
  bool saw_fault(proto::Outcome outcome) const {
    for (const auto& message : seen_) {
      if (message.has_fault() && message.fault().outcome() == outcome) return true;
    }
    return false;
  }
  MessageChannel& channel() { return channel_; }

 private:
  MessageChannel channel_;
  std::uint32_t last_id_ = 0;
  std::vector<proto::ControllerMessage> seen_;
};

// The next host is served (BUSY while the daemon has not yet seen the last one go).
void expect_next_host_served(const SimulatedDome& dome, std::chrono::milliseconds within) {
  const auto deadline = std::chrono::steady_clock::now() + within;
  for (;;) {
    try {
      auto client = dome.connect();
      EXPECT_EQ(client->info().led_count(), 96u);
      return;
    } catch (const Error& e) {
      ASSERT_LT(std::chrono::steady_clock::now(), deadline) << "still refused: " << e.what();
      std::this_thread::sleep_for(50ms);
    }
  }
}

TEST(ControllerAbuse, AHolderThatNeverSaysHelloLosesTheLockAtItsHelloTimeout) {
  SimulatedDome dome({{}, {}, {"--hello-timeout-ms", "500"}});
  RawHost idle(dome);  // connects, says nothing
  std::this_thread::sleep_for(100ms);
  try {
    dome.connect();
    FAIL() << "a second host was let in beside the first";
  } catch (const ControllerError& e) {
    EXPECT_EQ(e.code(), proto::Error::BUSY) << e.what();
    const std::string why = e.what();
    EXPECT_NE(why.find("connected since"), std::string::npos) << why;
    EXPECT_NE(why.find("no Hello yet"), std::string::npos) << why;
  }
  EXPECT_TRUE(idle.wait_for_hang_up(5s)) << "the idle holder kept the connection";
  EXPECT_TRUE(idle.saw_error(proto::Error::SESSION_EXPIRED));
  expect_next_host_served(dome, 5s);
}

TEST(ControllerAbuse, ASlowlorisLosesItsLeaseAndTheDomeGoesDark) {
  SimulatedDome dome({{}, {}, {"--idle-lease-ms", "600"}});
  RawHost trickler(dome);
  ASSERT_TRUE(trickler.hello(200));
  const auto on = trickler.set_led(8);
  ASSERT_TRUE(on && on->has_ack());
  std::atomic<bool> trickling{true};
  std::thread trickle([&] {
    const Bytes header = {'L', 'S', 0x00, 0x00, 0x01, 0x00};
    try {
      for (std::size_t i = 0; trickling; ++i) {
        trickler.write({header[i % header.size()]});
        std::this_thread::sleep_for(20ms);
      }
    } catch (const LinkClosed&) {
    }
  });
  const bool hung_up = trickler.wait_for_hang_up(10s);
  trickling = false;
  trickle.join();
  EXPECT_TRUE(hung_up) << "a slowloris kept the dome";
  EXPECT_TRUE(trickler.saw_error(proto::Error::SESSION_EXPIRED));
  const auto spans = dome.read_timeline().intervals("LED8");
  ASSERT_EQ(spans.size(), 1u);
  EXPECT_NE(spans[0].end_ns, kNever) << "LED 8 left on by a trickling host";
  expect_next_host_served(dome, 5s);
}

TEST(ControllerAbuse, FramesCutShortDoNotMakeTheDaemonDeaf) {
  SimulatedDome dome;
  RawHost host(dome);
  // Two frames cut short, each declaring far more than ever comes.
  Bytes first = protocol::encode_frame(Bytes(200'000, 0x11));
  first.resize(100);
  Bytes second = protocol::encode_frame(Bytes(900'000, 0x22));
  second.resize(50);
  host.write(first);
  host.write(second);
  const auto reply = host.hello();
  ASSERT_TRUE(reply) << "no answer to a Hello after two cut frames";
  EXPECT_TRUE(reply->has_info());
  // And a lone cut frame followed by silence is given up: the daemon says so.
  host.write(first);
  std::this_thread::sleep_for(1500ms);
  proto::HostMessage status;
  status.mutable_status();
  const auto answer = host.request(status);
  ASSERT_TRUE(answer);
  EXPECT_TRUE(answer->has_status());
  EXPECT_TRUE(host.saw_error(proto::Error::MALFORMED_FRAME));
}

TEST(ControllerAbuse, GarbageDoesNotKeepTheWatchdogFed) {
  SimulatedDome dome;
  RawHost host(dome);
  ASSERT_TRUE(host.hello(300));
  const auto lit = host.set_led(5);
  ASSERT_TRUE(lit && lit->has_ack());
  const Bytes garbage = {0x00, 0x13, 0x37};
  const auto until = std::chrono::steady_clock::now() + 1500ms;
  while (std::chrono::steady_clock::now() < until) {
    host.write(garbage);
    std::this_thread::sleep_for(20ms);
  }
  const std::int64_t garbage_end_ns = monotonic_now_ns();
  host.wait_for_hang_up(500ms);  // collects what the daemon said meanwhile
  EXPECT_TRUE(host.saw_fault(proto::WATCHDOG));
  const auto spans = dome.read_timeline().intervals("LED5");
  ASSERT_EQ(spans.size(), 1u);
  // Dark while the garbage still came (the LED's own limit is 2 s).
  EXPECT_LT(spans[0].end_ns, garbage_end_ns) << "garbage kept the watchdog fed";
}

TEST(ControllerAbuse, AFloodLeavesTheDomeDarkAndTheDaemonServing) {
  SimulatedDome dome;
  std::int64_t flood_end_ns = 0;
  {
    RawHost flooder(dome);
    ASSERT_TRUE(flooder.hello(300));
    const auto lit = flooder.set_led(3);
    ASSERT_TRUE(lit && lit->has_ack());
    std::thread reader([&] { flooder.wait_for_hang_up(4s); });
    // Empty messages, garbage and damaged frames as fast as the link takes them.
    Bytes damaged = protocol::encode_frame(Bytes(64, 0x5a));
    damaged.back() ^= 0xff;
    const Bytes empty = protocol::encode_frame(Bytes{});
    const Bytes garbage(512, 0x4c);  // 'L' without 'S': never a frame
    const auto until = std::chrono::steady_clock::now() + 1500ms;
    try {
      while (std::chrono::steady_clock::now() < until) {
        flooder.write(empty);
        flooder.write(damaged);
        flooder.write(garbage);
      }
    } catch (const LinkClosed&) {
    }
    flood_end_ns = monotonic_now_ns();
    reader.join();
    EXPECT_TRUE(flooder.saw_fault(proto::WATCHDOG));
  }
  const auto spans = dome.read_timeline().intervals("LED3");
  ASSERT_EQ(spans.size(), 1u);
  EXPECT_LT(spans[0].end_ns, flood_end_ns) << "the flood kept the watchdog fed (LED 3 lit throughout)";
  expect_next_host_served(dome, 10s);
  EXPECT_TRUE(dome.firmware().running());
}

}  // namespace
}  // namespace lightstage::testing
