// The host's controller client against a scripted controller in this process.
#include "lightstage/host/controller/controller_client.hpp"
#include "lightstage/common/message_channel.hpp"
#include "lightstage/common/socket_link.hpp"
#include "lightstage/host/controller/sequences.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <functional>
#include <thread>

namespace lightstage {
namespace {

using std::chrono::milliseconds;

// Answers Hello with Info, then hands every other message to `handle`.
class FakeController {
 public:
  using Handler = std::function<void(const proto::HostMessage&, MessageChannel&)>;

  FakeController(std::unique_ptr<ByteLink> link, Handler handle) : channel_(std::move(link)) {
    thread_ = std::thread([this, handle = std::move(handle)] {
      try {
        for (;;) {
          proto::HostMessage m;
          if (!channel_.receive(m, milliseconds(50))) {
            if (stop_) return;
            continue;
          }
          if (m.has_heartbeat()) {
            ++heartbeats_;
            continue;
          }
          if (m.has_hello()) {
            proto::ControllerMessage reply;
            reply.set_request_id(m.request_id());
            reply.mutable_info()->set_protocol_version(1);
            reply.mutable_info()->set_led_count(3);
            for (std::uint32_t id : {4u, 5u, 6u}) reply.mutable_info()->add_leds()->set_id(id);
            channel_.send(reply);
            continue;
          }
          handle(m, channel_);
        }
      } catch (const LinkClosed&) {
      }
    });
  }
  ~FakeController() {
    stop_ = true;
    thread_.join();
  }
  int heartbeats() const { return heartbeats_; }
  void drop() { channel_.link().shutdown(); }

 private:
  MessageChannel channel_;
  std::atomic<bool> stop_{false};
  std::atomic<int> heartbeats_{0};
  std::thread thread_;
};

proto::ControllerMessage ack(const proto::HostMessage& m) {
  proto::ControllerMessage reply;
  reply.set_request_id(m.request_id());
  reply.mutable_ack();
  return reply;
}

TEST(ControllerClient, NegotiatesAndSendsHeartbeats) {
  auto [host_end, controller_end] = socket_link_pair();
  FakeController controller(std::move(controller_end),
                            [](const proto::HostMessage& m, MessageChannel& c) { c.send(ack(m)); });
  ControllerClientOptions options;
  options.heartbeat_period = milliseconds(10);
  ControllerClient client(std::move(host_end), options);
  EXPECT_EQ(client.info().led_count(), 3u);
  EXPECT_EQ(led_ids(client.info()), (std::vector<std::uint32_t>{4, 5, 6}));
  std::this_thread::sleep_for(milliseconds(200));
  EXPECT_GE(controller.heartbeats(), 3);
}

TEST(ControllerClient, ErrorRepliesBecomeControllerErrorsWithTheirCode) {
  auto [host_end, controller_end] = socket_link_pair();
  FakeController controller(std::move(controller_end), [](const proto::HostMessage& m, MessageChannel& c) {
    proto::ControllerMessage reply;
    reply.set_request_id(m.request_id());
    reply.mutable_error()->set_code(proto::Error::SAFETY_LIMIT);
    reply.mutable_error()->set_message("LED 4 would exceed its duty cycle");
    c.send(reply);
  });
  ControllerClient client(std::move(host_end));
  try {
    client.set_leds({{4, 1.0f}});
    FAIL();
  } catch (const ControllerError& e) {
    EXPECT_EQ(e.code(), proto::Error::SAFETY_LIMIT);
    EXPECT_NE(std::string(e.what()).find("duty cycle"), std::string::npos);
  }
}

// A controller that already serves another host sends BUSY unasked and hangs
// up: the caller must learn that, not only that the link closed.
TEST(ControllerClient, ARefusalBeforeTheHandshakeIsAControllerError) {
  auto [host_end, controller_end] = socket_link_pair();
  std::thread refuse([link = std::move(controller_end)]() mutable {
    MessageChannel channel(std::move(link));
    proto::ControllerMessage busy;
    busy.mutable_error()->set_code(proto::Error::BUSY);
    busy.mutable_error()->set_message("another host controls this dome; try again later");
    channel.send(busy);
    channel.link().shutdown();
  });
  try {
    ControllerClient client(std::move(host_end));
    ADD_FAILURE() << "connected to a controller that refused";
  } catch (const ControllerError& e) {
    EXPECT_EQ(e.code(), proto::Error::BUSY);
    EXPECT_NE(std::string(e.what()).find("another host"), std::string::npos) << e.what();
  }
  refuse.join();
}

// An error the controller reported earlier and got past (a malformed frame)
// is not the reason for a later hang-up.
TEST(ControllerClient, AnEarlierUnaskedErrorDoesNotExplainALaterHangUp) {
  auto [host_end, controller_end] = socket_link_pair();
  FakeController* fake = nullptr;
  FakeController controller(std::move(controller_end), [&](const proto::HostMessage& m, MessageChannel& c) {
    if (m.has_status()) {
      proto::ControllerMessage malformed;
      malformed.mutable_error()->set_code(proto::Error::MALFORMED_FRAME);
      malformed.mutable_error()->set_message("frame CRC mismatch");
      c.send(malformed);
      proto::ControllerMessage status;
      status.set_request_id(m.request_id());
      status.mutable_status();
      c.send(status);
      return;
    }
    fake->drop();
  });
  fake = &controller;
  ControllerClient client(std::move(host_end));
  client.status();
  EXPECT_THROW(client.abort(), LinkClosed);
}

TEST(ControllerClient, NoReplyTimesOut) {
  auto [host_end, controller_end] = socket_link_pair();
  FakeController controller(std::move(controller_end), [](const proto::HostMessage&, MessageChannel&) {});
  ControllerClientOptions options;
  options.reply_timeout = milliseconds(100);
  ControllerClient client(std::move(host_end), options);
  EXPECT_THROW(client.status(), ControllerError);
}

TEST(ControllerClient, RunSequenceCollectsStepEventsUntilDone) {
  auto [host_end, controller_end] = socket_link_pair();
  FakeController controller(std::move(controller_end), [](const proto::HostMessage& m, MessageChannel& c) {
    c.send(ack(m));
    if (!m.has_run()) return;
    for (std::uint32_t k = 0; k < 3; ++k) {
      proto::ControllerMessage e;
      e.mutable_step_event()->set_sequence_id(m.run().sequence_id());
      e.mutable_step_event()->set_step(k);
      e.mutable_step_event()->set_lateness_ns(1000 * (k + 1));
      c.send(e);
    }
    proto::ControllerMessage done;
    done.mutable_sequence_done()->set_sequence_id(m.run().sequence_id());
    done.mutable_sequence_done()->set_steps_run(3);
    c.send(done);
  });
  ControllerClient client(std::move(host_end));
  int seen = 0;
  const SequenceRun run =
      client.run_sequence(one_led_per_step({4, 5, 6}, {}, 12), [&](const proto::StepEvent&) { ++seen; });
  EXPECT_TRUE(run.ok());
  EXPECT_EQ(seen, 3);
  ASSERT_EQ(run.steps.size(), 3u);
  const LatenessStats stats = lateness_stats(run.steps);
  EXPECT_EQ(stats.median_ns, 2000);
  EXPECT_EQ(stats.max_ns, 3000);
}

TEST(ControllerClient, ALinkDroppedMidSequenceIsLinkClosed) {
  auto [host_end, controller_end] = socket_link_pair();
  FakeController* fake = nullptr;
  FakeController controller(std::move(controller_end), [&](const proto::HostMessage& m, MessageChannel& c) {
    c.send(ack(m));
    if (m.has_run()) fake->drop();
  });
  fake = &controller;
  ControllerClient client(std::move(host_end));
  EXPECT_THROW(client.run_sequence(one_led_per_step({4}, {}, 1), {}, std::chrono::seconds(10)), LinkClosed);
}

TEST(Sequences, OneLedPerStepCarriesTheTimingAndTags) {
  OneLedPerStepOptions options;
  options.settle_us = 11;
  options.exposure_us = 22;
  options.gap_us = 33;
  options.closed_loop = true;
  const proto::Sequence s = one_led_per_step({7, 3}, options, 9);
  EXPECT_EQ(s.id(), 9u);
  ASSERT_EQ(s.steps_size(), 2);
  EXPECT_EQ(s.steps(1).leds(0).led_id(), 3u);
  EXPECT_EQ(s.steps(1).tag(), 1u);
  EXPECT_EQ(s.steps(0).settle_us(), 11u);
  EXPECT_EQ(s.steps(0).exposure_us(), 22u);
  EXPECT_EQ(s.steps(0).gap_us(), 33u);
  EXPECT_TRUE(s.steps(0).wait_strobe());
  EXPECT_TRUE(s.steps(0).trigger());
}

TEST(Sequences, LatenessStatsPercentiles) {
  std::vector<proto::StepEvent> steps(100);
  for (int i = 0; i < 100; ++i) steps[static_cast<std::size_t>(i)].set_lateness_ns(i + 1);
  const LatenessStats s = lateness_stats(steps);
  EXPECT_EQ(s.steps, 100u);
  EXPECT_DOUBLE_EQ(s.median_ns, 50.5);
  EXPECT_DOUBLE_EQ(s.p99_ns, 99);
  EXPECT_DOUBLE_EQ(s.max_ns, 100);
  EXPECT_EQ(lateness_stats({}).steps, 0u);
}

}  // namespace
}  // namespace lightstage
