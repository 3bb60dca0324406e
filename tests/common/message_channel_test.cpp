// A MessageChannel carries protobuf messages over any ByteLink. Whatever the
// peer sends, receive() yields whole messages, throws ProtocolError for bad
// frames and payloads and stays usable afterwards, and throws LinkClosed only
// when the link is gone.
#include "lightstage/common/message_channel.hpp"
#include "lightstage/common/framing.hpp"
#include "lightstage/common/socket_link.hpp"
#include "lightstage/proto/controller.pb.h"

#include <gtest/gtest.h>

#include <deque>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace lightstage {
namespace {

using namespace std::chrono_literals;
using Bytes = std::vector<std::uint8_t>;

// A link that delivers scripted chunks, one per read() (a read with a smaller
// buffer leaves the rest of the chunk for the next), then times out or, once
// closed, throws LinkClosed. Counts reads so tests can tell when bytes were asked for.
class ScriptedLink final : public ByteLink {
 public:
  void deliver(Bytes chunk) {
    const std::lock_guard lock(mutex_);
    chunks_.push_back(std::move(chunk));
  }
  void close_after_chunks() {
    const std::lock_guard lock(mutex_);
    close_when_empty_ = true;
  }
  Bytes written() const {
    const std::lock_guard lock(mutex_);
    return written_;
  }
  int reads() const {
    const std::lock_guard lock(mutex_);
    return reads_;
  }

  std::size_t read(std::span<std::uint8_t> buffer, std::chrono::milliseconds timeout) override {
    {
      const std::lock_guard lock(mutex_);
      ++reads_;
      if (closed_) throw LinkClosed("scripted: closed");
      if (!chunks_.empty()) {
        Bytes& chunk = chunks_.front();
        const std::size_t n = std::min(buffer.size(), chunk.size());
        std::copy_n(chunk.begin(), n, buffer.begin());
        chunk.erase(chunk.begin(), chunk.begin() + static_cast<std::ptrdiff_t>(n));
        if (chunk.empty()) chunks_.pop_front();
        return n;
      }
      if (close_when_empty_) throw LinkClosed("scripted: closed by the peer");
    }
    std::this_thread::sleep_for(std::min(timeout, std::chrono::milliseconds(5)));
    return 0;
  }
  void write(std::span<const std::uint8_t> bytes) override {
    const std::lock_guard lock(mutex_);
    if (closed_) throw LinkClosed("scripted: closed");
    written_.insert(written_.end(), bytes.begin(), bytes.end());
  }
  void shutdown() override {
    const std::lock_guard lock(mutex_);
    closed_ = true;
  }
  std::string describe() const override { return "scripted:test"; }

 private:
  mutable std::mutex mutex_;
  std::deque<Bytes> chunks_;
  Bytes written_;
  bool close_when_empty_ = false;
  bool closed_ = false;
  int reads_ = 0;
};

proto::HostMessage heartbeat(std::uint64_t counter) {
  proto::HostMessage message;
  message.mutable_heartbeat()->set_counter(counter);
  return message;
}

Bytes frame_of(const google::protobuf::MessageLite& message) {
  const std::string bytes = message.SerializeAsString();
  return protocol::encode_frame(std::span(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()));
}

Bytes frame_of_bytes(const Bytes& payload) { return protocol::encode_frame(payload); }

struct ScriptedChannel {
  ScriptedLink* link;
  MessageChannel channel;
  ScriptedChannel() : ScriptedChannel(std::make_unique<ScriptedLink>()) {}

 private:
  explicit ScriptedChannel(std::unique_ptr<ScriptedLink> owned)
      : link(owned.get()), channel(std::move(owned)) {}
};

TEST(MessageChannel, SentMessageIsOneFrameOfItsSerialization) {
  ScriptedChannel c;
  proto::HostMessage hello;
  hello.set_request_id(3);
  hello.mutable_hello()->set_protocol_version(1);
  c.channel.send(hello);
  EXPECT_EQ(c.link->written(), frame_of(hello));
}

TEST(MessageChannel, MessageSplitIntoSingleBytesIsReassembled) {
  ScriptedChannel c;
  const Bytes frame = frame_of(heartbeat(42));
  for (const auto byte : frame) c.link->deliver({byte});
  proto::HostMessage received;
  ASSERT_TRUE(c.channel.receive(received, 5s));
  EXPECT_EQ(received.heartbeat().counter(), 42u);
}

TEST(MessageChannel, MessagesMergedInOneReadComeOutOneByOneWithoutMoreReads) {
  ScriptedChannel c;
  Bytes merged;
  for (std::uint64_t i = 1; i <= 3; ++i) {
    const Bytes frame = frame_of(heartbeat(i));
    merged.insert(merged.end(), frame.begin(), frame.end());
  }
  c.link->deliver(merged);
  proto::HostMessage received;
  ASSERT_TRUE(c.channel.receive(received, 5s));
  EXPECT_EQ(received.heartbeat().counter(), 1u);
  const int reads_after_first = c.link->reads();
  ASSERT_TRUE(c.channel.receive(received, 5s));
  EXPECT_EQ(received.heartbeat().counter(), 2u);
  ASSERT_TRUE(c.channel.receive(received, 5s));
  EXPECT_EQ(received.heartbeat().counter(), 3u);
  EXPECT_EQ(c.link->reads(), reads_after_first);
}

TEST(MessageChannel, ReceiveTimesOutWithoutAMessage) {
  ScriptedChannel c;
  const Bytes frame = frame_of(heartbeat(1));
  c.link->deliver(Bytes(frame.begin(), frame.begin() + 4));  // part of a header
  proto::HostMessage received;
  EXPECT_FALSE(c.channel.receive(received, 30ms));
  EXPECT_FALSE(c.channel.receive(received, 0ms));
}

// Runs receive() until it yields a message, collecting the ProtocolErrors on the way.
std::vector<std::string> errors_until_message(MessageChannel& channel, proto::HostMessage& message) {
  std::vector<std::string> errors;
  for (int attempt = 0; attempt < 100; ++attempt) {
    try {
      if (channel.receive(message, 5s)) return errors;
      ADD_FAILURE() << "timed out";
      return errors;
    } catch (const ProtocolError& error) {
      errors.emplace_back(error.what());
    }
  }
  ADD_FAILURE() << "no message after 100 errors";
  return errors;
}

TEST(MessageChannel, GarbageBeforeAFrameIsOneProtocolErrorThenTheMessage) {
  ScriptedChannel c;
  const std::string noise = "AT+GMR\r\n";  // e.g. a modem manager probing a fresh tty
  c.link->deliver(Bytes(noise.begin(), noise.end()));
  c.link->deliver(frame_of(heartbeat(7)));
  proto::HostMessage received;
  const auto errors = errors_until_message(c.channel, received);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("scripted:test"), std::string::npos) << errors[0];
  EXPECT_EQ(received.heartbeat().counter(), 7u);
}

TEST(MessageChannel, CorruptCrcIsAProtocolErrorAndTheNextMessageArrives) {
  ScriptedChannel c;
  Bytes bad = frame_of(heartbeat(1));
  bad[protocol::kHeaderSize] ^= 0xff;
  c.link->deliver(bad);
  c.link->deliver(frame_of(heartbeat(2)));
  proto::HostMessage received;
  const auto errors = errors_until_message(c.channel, received);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("CRC"), std::string::npos) << errors[0];
  EXPECT_EQ(received.heartbeat().counter(), 2u);
}

TEST(MessageChannel, OversizeLengthIsAProtocolErrorAndTheNextMessageArrives) {
  ScriptedChannel c;
  c.link->deliver({'L', 'S', 0xff, 0xff, 0xff, 0x7f});
  c.link->deliver(frame_of(heartbeat(5)));
  proto::HostMessage received;
  const auto errors = errors_until_message(c.channel, received);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("exceeds"), std::string::npos) << errors[0];
  EXPECT_EQ(received.heartbeat().counter(), 5u);
}

TEST(MessageChannel, PayloadThatIsNotTheMessageTypeIsAProtocolErrorAndTheChannelGoesOn) {
  ScriptedChannel c;
  // A well-framed payload that is no protobuf message: wire type 7 does not exist.
  c.link->deliver(frame_of_bytes({0x0f, 0x01, 0x02}));
  // A truncated length-delimited field: field 2 claims 100 bytes, has 1.
  c.link->deliver(frame_of_bytes({0x12, 0x64, 0x00}));
  c.link->deliver(frame_of(heartbeat(9)));
  proto::HostMessage received;
  for (int bad = 0; bad < 2; ++bad) {
    try {
      c.channel.receive(received, 5s);
      ADD_FAILURE() << "bad payload " << bad << " was accepted";
    } catch (const ProtocolError& error) {
      EXPECT_NE(std::string(error.what()).find("lightstage.proto.HostMessage"), std::string::npos)
          << error.what();
    }
  }
  ASSERT_TRUE(c.channel.receive(received, 5s));
  EXPECT_EQ(received.heartbeat().counter(), 9u);
}

// A host killed in the middle of a frame (serial and USB links survive it):
// the next host's Hello must get through, after one ProtocolError.
TEST(MessageChannel, HelloAfterAFrameCutShortGetsThrough) {
  ScriptedChannel c;
  proto::HostMessage upload;
  upload.set_request_id(8);
  for (int i = 0; i < 100; ++i)
    upload.mutable_upload()->mutable_sequence()->add_steps()->set_exposure_us(1000);
  const Bytes cut = frame_of(upload);
  c.link->deliver(Bytes(cut.begin(), cut.begin() + static_cast<std::ptrdiff_t>(cut.size() / 2)));
  proto::HostMessage received;
  EXPECT_FALSE(c.channel.receive(received, 20ms));
  proto::HostMessage hello;
  hello.set_request_id(1);
  hello.mutable_hello()->set_protocol_version(1);
  c.link->deliver(frame_of(hello));
  const auto errors = errors_until_message(c.channel, received);
  EXPECT_EQ(errors.size(), 1u);
  EXPECT_TRUE(received.has_hello());
  EXPECT_EQ(received.request_id(), 1u);
}

// A peer that stops mid-frame costs a bounded wait: the frame begun is given
// up (a ProtocolError) after the partial-frame timeout without a byte, and
// the next message gets through.
TEST(MessageChannel, FrameAbandonedMidWayIsAProtocolErrorAfterTheTimeout) {
  auto owned = std::make_unique<ScriptedLink>();
  ScriptedLink& link = *owned;
  MessageChannel channel(std::move(owned), 100ms);
  const Bytes cut = frame_of_bytes(Bytes(5000, 0x66));
  link.deliver(Bytes(cut.begin(), cut.begin() + 50));
  proto::HostMessage message;
  const auto start = std::chrono::steady_clock::now();
  try {
    channel.receive(message, 5s);
    FAIL() << "a frame cut short was waited for";
  } catch (const ProtocolError& e) {
    EXPECT_NE(std::string(e.what()).find("abandoned 50 of the 5010 bytes"), std::string::npos) << e.what();
  }
  EXPECT_LT(std::chrono::steady_clock::now() - start, 4s) << "gave up only at the receive timeout";
  link.deliver(frame_of(heartbeat(7)));
  ASSERT_TRUE(channel.receive(message, 1s));
  EXPECT_EQ(message.heartbeat().counter(), 7u);
}

TEST(MessageChannel, EmptyPayloadIsAnEmptyMessage) {
  ScriptedChannel c;
  c.link->deliver(frame_of_bytes({}));
  proto::HostMessage received = heartbeat(1);
  ASSERT_TRUE(c.channel.receive(received, 5s));
  EXPECT_EQ(received.body_case(), proto::HostMessage::BODY_NOT_SET);
}

TEST(MessageChannel, MessagesBeforeAHangUpAreDeliveredThenLinkClosed) {
  ScriptedChannel c;
  c.link->deliver(frame_of(heartbeat(1)));
  c.link->close_after_chunks();
  proto::HostMessage received;
  ASSERT_TRUE(c.channel.receive(received, 5s));
  EXPECT_EQ(received.heartbeat().counter(), 1u);
  EXPECT_THROW(c.channel.receive(received, 5s), LinkClosed);
}

TEST(MessageChannel, SendAfterShutdownThrowsLinkClosed) {
  ScriptedChannel c;
  c.channel.link().shutdown();
  EXPECT_THROW(c.channel.send(heartbeat(1)), LinkClosed);
}

// Over a real socket pair: both directions, and frames from concurrent
// senders never interleave.
TEST(MessageChannel, ConcurrentSendersOverASocketPairNeverInterleaveFrames) {
  auto [a, b] = socket_link_pair();
  MessageChannel sender(std::move(a));
  MessageChannel receiver(std::move(b));
  constexpr int kThreads = 4;
  constexpr int kPerThread = 200;
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&sender, t] {
      for (int i = 0; i < kPerThread; ++i) {
        proto::HostMessage message;
        message.set_request_id(static_cast<std::uint32_t>(t));
        auto* leds = message.mutable_set_leds();
        for (int led = 0; led < 50; ++led) leds->add_leds()->set_led_id(static_cast<std::uint32_t>(i));
        sender.send(message);
      }
    });
  }
  std::vector<int> next_index(kThreads, 0);
  for (int n = 0; n < kThreads * kPerThread; ++n) {
    proto::HostMessage received;
    ASSERT_TRUE(receiver.receive(received, 10s)) << "message " << n;
    const auto t = received.request_id();
    ASSERT_LT(t, static_cast<std::uint32_t>(kThreads));
    ASSERT_EQ(received.set_leds().leds_size(), 50);
    // Each sender's messages arrive in its own order.
    EXPECT_EQ(received.set_leds().leds(0).led_id(), static_cast<std::uint32_t>(next_index[t]));
    ++next_index[t];
  }
  for (auto& thread : threads) thread.join();

  proto::ControllerMessage reply;
  reply.set_request_id(1);
  reply.mutable_ack();
  receiver.send(reply);
  proto::ControllerMessage got;
  ASSERT_TRUE(sender.receive(got, 10s));
  EXPECT_TRUE(got.has_ack());
}

}  // namespace
}  // namespace lightstage
