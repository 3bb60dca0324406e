// The frame decoder sees whatever a wire delivers: frames split over reads,
// several in one read, garbage, damaged frames. Every good frame must come out
// whole and in order, every bad run must be reported once and skipped.
#include "lightstage/common/framing.hpp"
#include "lightstage/common/error.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace lightstage::protocol {
namespace {

using Bytes = std::vector<std::uint8_t>;

Bytes bytes_of(const std::string& text) { return Bytes(text.begin(), text.end()); }

Bytes concat(std::initializer_list<Bytes> parts) {
  Bytes out;
  for (const auto& part : parts) out.insert(out.end(), part.begin(), part.end());
  return out;
}

// Everything the decoder yields for the bytes it has been fed so far.
struct Drained {
  std::vector<Bytes> frames;
  std::vector<std::string> errors;
};

Drained drain(FrameDecoder& decoder) {
  Drained out;
  while (auto frame = decoder.next()) {
    if (frame->error.empty()) {
      out.frames.push_back(frame->payload);
    } else {
      out.errors.push_back(frame->error);
    }
  }
  return out;
}

TEST(Framing, LayoutIsMagicLengthPayloadCrc) {
  const Bytes frame = encode_frame(bytes_of("123456789"));
  ASSERT_EQ(frame.size(), kHeaderSize + 9 + kTrailerSize);
  EXPECT_EQ(frame[0], 'L');
  EXPECT_EQ(frame[1], 'S');
  EXPECT_EQ(Bytes(frame.begin() + 2, frame.begin() + 6), (Bytes{9, 0, 0, 0}));
  EXPECT_EQ(Bytes(frame.begin() + 6, frame.begin() + 15), bytes_of("123456789"));
  // CRC-32 (zlib, IEEE) check value of "123456789" is 0xCBF43926, little endian.
  EXPECT_EQ(Bytes(frame.end() - 4, frame.end()), (Bytes{0x26, 0x39, 0xf4, 0xcb}));
}

TEST(Framing, RoundTripsEmptySmallAndLargestPayloads) {
  std::mt19937 random(7);
  for (const std::size_t size : {std::size_t{0}, std::size_t{1}, std::size_t{300}, kMaxPayload}) {
    Bytes payload(size);
    for (auto& byte : payload) byte = static_cast<std::uint8_t>(random());
    FrameDecoder decoder;
    decoder.feed(encode_frame(payload));
    const Drained out = drain(decoder);
    ASSERT_EQ(out.frames.size(), 1u) << size;
    EXPECT_TRUE(out.errors.empty()) << size;
    EXPECT_EQ(out.frames[0], payload) << size;
    EXPECT_EQ(decoder.buffered(), 0u);
  }
}

TEST(Framing, EncodeRefusesAnOversizePayload) {
  const Bytes payload(kMaxPayload + 1);
  EXPECT_THROW(encode_frame(payload), Error);
}

TEST(Framing, FrameFedByteByByteComesOutOnceWhenComplete) {
  const Bytes frame = encode_frame(bytes_of("hello"));
  FrameDecoder decoder;
  for (std::size_t i = 0; i + 1 < frame.size(); ++i) {
    decoder.feed(std::span(&frame[i], 1));
    EXPECT_FALSE(decoder.next().has_value()) << "after byte " << i;
  }
  decoder.feed(std::span(&frame.back(), 1));
  const Drained out = drain(decoder);
  ASSERT_EQ(out.frames.size(), 1u);
  EXPECT_EQ(out.frames[0], bytes_of("hello"));
  EXPECT_TRUE(out.errors.empty());
}

TEST(Framing, SeveralFramesInOneFeedComeOutInOrder) {
  FrameDecoder decoder;
  decoder.feed(
      concat({encode_frame(bytes_of("one")), encode_frame(bytes_of("")), encode_frame(bytes_of("three"))}));
  const Drained out = drain(decoder);
  EXPECT_EQ(out.frames, (std::vector<Bytes>{bytes_of("one"), bytes_of(""), bytes_of("three")}));
  EXPECT_TRUE(out.errors.empty());
}

TEST(Framing, GarbageBeforeAFrameIsReportedOnceThenTheFrameFollows) {
  FrameDecoder decoder;
  decoder.feed(concat({bytes_of("noise L noise LX"), encode_frame(bytes_of("payload"))}));
  auto first = decoder.next();
  ASSERT_TRUE(first.has_value());
  EXPECT_NE(first->error.find("dropped 16 byte(s)"), std::string::npos) << first->error;
  const Drained rest = drain(decoder);
  EXPECT_EQ(rest.frames, std::vector<Bytes>{bytes_of("payload")});
  EXPECT_TRUE(rest.errors.empty());
}

TEST(Framing, CorruptCrcDropsTheFrameAndKeepsTheNext) {
  Bytes bad = encode_frame(bytes_of("damaged on the wire"));
  bad[kHeaderSize + 3] ^= 0x10;
  FrameDecoder decoder;
  decoder.feed(concat({bad, encode_frame(bytes_of("intact"))}));
  const Drained out = drain(decoder);
  ASSERT_EQ(out.errors.size(), 1u);
  EXPECT_NE(out.errors[0].find("failed its CRC"), std::string::npos) << out.errors[0];
  EXPECT_NE(out.errors[0].find(fmt::format("dropped {} byte(s)", bad.size())), std::string::npos)
      << out.errors[0];
  EXPECT_EQ(out.frames, std::vector<Bytes>{bytes_of("intact")});
}

TEST(Framing, CorruptCrcFieldItselfIsRejected) {
  Bytes bad = encode_frame(bytes_of("x"));
  bad.back() ^= 0x01;
  FrameDecoder decoder;
  decoder.feed(bad);
  const Drained out = drain(decoder);
  EXPECT_TRUE(out.frames.empty());
  ASSERT_EQ(out.errors.size(), 1u);
  EXPECT_EQ(decoder.buffered(), 0u);
}

TEST(Framing, OversizeLengthIsRejectedWithoutWaitingForItsBytes) {
  FrameDecoder decoder;
  const Bytes bogus = {'L', 'S', 0x01, 0x00, 0x10, 0x00};  // 0x100001 = kMaxPayload + 1
  decoder.feed(concat({bogus, encode_frame(bytes_of("after"))}));
  const Drained out = drain(decoder);
  ASSERT_EQ(out.errors.size(), 1u);
  EXPECT_NE(out.errors[0].find("exceeds"), std::string::npos) << out.errors[0];
  EXPECT_EQ(out.frames, std::vector<Bytes>{bytes_of("after")});
}

TEST(Framing, LengthAtTheLimitIsAwaitedNotRejected) {
  FrameDecoder decoder;
  const Bytes header = {'L', 'S', 0x00, 0x00, 0x10, 0x00};  // exactly kMaxPayload
  decoder.feed(header);
  EXPECT_FALSE(decoder.next().has_value());
  EXPECT_EQ(decoder.buffered(), header.size());
}

TEST(Framing, LoneMagicByteAtTheEndIsKeptForTheNextFeed) {
  const Bytes frame = encode_frame(bytes_of("split magic"));
  FrameDecoder decoder;
  decoder.feed(concat({bytes_of("zz"), Bytes{frame[0]}}));
  auto report = decoder.next();
  ASSERT_TRUE(report.has_value());
  EXPECT_FALSE(report->error.empty());
  EXPECT_FALSE(decoder.next().has_value());
  EXPECT_EQ(decoder.buffered(), 1u);
  decoder.feed(std::span(frame).subspan(1));
  const Drained out = drain(decoder);
  EXPECT_EQ(out.frames, std::vector<Bytes>{bytes_of("split magic")});
  EXPECT_TRUE(out.errors.empty());
}

// A sender that died mid-frame leaves a partial frame; the next sender's
// first complete frame must not be swallowed as the rest of it.
TEST(Framing, FrameCutShortIsDroppedWhenACompleteFrameFollows) {
  const Bytes cut = encode_frame(Bytes(1000, 0x11));
  FrameDecoder decoder;
  decoder.feed(std::span(cut).first(200));
  EXPECT_FALSE(decoder.next().has_value());
  decoder.feed(encode_frame(bytes_of("hello again")));
  const Drained out = drain(decoder);
  ASSERT_EQ(out.errors.size(), 1u);
  EXPECT_NE(out.errors[0].find("dropped 200 byte(s)"), std::string::npos) << out.errors[0];
  EXPECT_NE(out.errors[0].find("cut short"), std::string::npos) << out.errors[0];
  EXPECT_EQ(out.frames, std::vector<Bytes>{bytes_of("hello again")});
}

// Two senders that died mid-frame one after the other: the complete frame
// after both must come out as soon as it is in, not once the first cut
// frame's declared length has arrived.
TEST(Framing, TwoFramesCutShortInARowDoNotHideTheNextFrame) {
  const Bytes first = encode_frame(Bytes(100'000, 0x11));
  const Bytes second = encode_frame(Bytes(5'000, 0x22));
  FrameDecoder decoder;
  decoder.feed(std::span(first).first(300));
  decoder.feed(std::span(second).first(40));
  EXPECT_FALSE(decoder.next().has_value());
  decoder.feed(encode_frame(bytes_of("still listening")));
  const Drained out = drain(decoder);
  ASSERT_EQ(out.errors.size(), 1u);
  EXPECT_NE(out.errors[0].find("dropped 340 byte(s)"), std::string::npos) << out.errors[0];
  EXPECT_NE(out.errors[0].find("cut short"), std::string::npos) << out.errors[0];
  EXPECT_EQ(out.frames, std::vector<Bytes>{bytes_of("still listening")});
  EXPECT_EQ(decoder.buffered(), 0u);
}

// Thousands of short cut frames in small reads (a hostile or broken sender),
// then a good frame: it is found the moment it has arrived.
TEST(Framing, ManyCutFramesThenAGoodOneFedInSmallReads) {
  Bytes wire;
  const Bytes big = encode_frame(Bytes(kMaxPayload, 0x33));
  wire.insert(wire.end(), big.begin(), big.begin() + 64);
  const Bytes partial = encode_frame(Bytes(200, 0x44));
  for (int i = 0; i < 3000; ++i) wire.insert(wire.end(), partial.begin(), partial.begin() + 30);
  FrameDecoder decoder;
  for (std::size_t at = 0; at < wire.size(); at += 256) {
    decoder.feed(std::span(wire).subspan(at, std::min<std::size_t>(256, wire.size() - at)));
    const Drained out = drain(decoder);
    ASSERT_TRUE(out.frames.empty());
  }
  decoder.feed(encode_frame(bytes_of("hello")));
  const Drained out = drain(decoder);
  EXPECT_EQ(out.frames, std::vector<Bytes>{bytes_of("hello")});
  EXPECT_EQ(decoder.buffered(), 0u);
}

// A frame abandoned (its sender went quiet) is reported with how much of it
// came, and a frame that began inside it is still found.
TEST(Framing, AbandonedPartialFrameIsReportedAndTheDecoderResynchronises) {
  FrameDecoder decoder;
  EXPECT_FALSE(decoder.abandon_partial().has_value());
  const Bytes cut = encode_frame(Bytes(1000, 0x55));
  const Bytes good = encode_frame(bytes_of("after the gap"));
  decoder.feed(std::span(cut).first(100));
  decoder.feed(std::span(good).first(5));
  EXPECT_FALSE(decoder.next().has_value());
  const auto report = decoder.abandon_partial();
  ASSERT_TRUE(report.has_value());
  EXPECT_NE(report->error.find("105 of the 1010 bytes"), std::string::npos) << report->error;
  decoder.feed(std::span(good).subspan(5));
  const Drained out = drain(decoder);
  EXPECT_EQ(out.frames, std::vector<Bytes>{bytes_of("after the gap")});
}

// The look-ahead must not break a long frame whose payload holds magic bytes
// and frame-like headers (here with wrong CRCs), arriving a few bytes at a time.
TEST(Framing, LongFrameWithFrameLikeBytesInsideArrivesIntact) {
  Bytes payload;
  for (int i = 0; i < 300; ++i) {
    const Bytes fake = {'L', 'S', 3, 0, 0, 0, 'a', 'b', 'c', 0xde, 0xad, 0xbe, 0xef};
    payload.insert(payload.end(), fake.begin(), fake.end());
  }
  payload.push_back('L');
  const Bytes frame = encode_frame(payload);
  FrameDecoder decoder;
  std::vector<Bytes> frames;
  for (std::size_t at = 0; at < frame.size(); at += 7) {
    decoder.feed(std::span(frame).subspan(at, std::min<std::size_t>(7, frame.size() - at)));
    Drained out = drain(decoder);
    EXPECT_TRUE(out.errors.empty()) << out.errors.front();
    frames.insert(frames.end(), out.frames.begin(), out.frames.end());
  }
  EXPECT_EQ(frames, std::vector<Bytes>{payload});
}

// Many frames with garbage between them, fed in random chunk sizes: every
// frame comes out intact and in order, and no report lumps two frames together.
TEST(Framing, RandomSplitsAndGarbageNeverLoseOrReorderFrames) {
  std::mt19937 random(20261123);
  for (int round = 0; round < 20; ++round) {
    std::vector<Bytes> payloads;
    Bytes wire;
    for (int i = 0; i < 50; ++i) {
      if (random() % 3 == 0) {
        // Garbage without the magic's first byte, so it cannot open a bogus frame.
        Bytes garbage(1 + random() % 20);
        for (auto& byte : garbage) {
          do byte = static_cast<std::uint8_t>(random());
          while (byte == kMagic0);
        }
        wire.insert(wire.end(), garbage.begin(), garbage.end());
      }
      Bytes payload(random() % 200);
      for (auto& byte : payload) byte = static_cast<std::uint8_t>(random());
      const Bytes frame = encode_frame(payload);
      wire.insert(wire.end(), frame.begin(), frame.end());
      payloads.push_back(std::move(payload));
    }
    FrameDecoder decoder;
    std::vector<Bytes> frames;
    std::size_t at = 0;
    while (at < wire.size()) {
      const std::size_t chunk = std::min<std::size_t>(wire.size() - at, 1 + random() % 64);
      decoder.feed(std::span(wire).subspan(at, chunk));
      at += chunk;
      Drained out = drain(decoder);
      frames.insert(frames.end(), out.frames.begin(), out.frames.end());
    }
    EXPECT_EQ(frames, payloads) << "round " << round;
    EXPECT_EQ(decoder.buffered(), 0u);
  }
}

// Random bytes rich in magic bytes, fed in random chunks, never crash or make
// the decoder hold more than one maximum frame.
TEST(Framing, ArbitraryBytesKeepTheBufferBounded) {
  std::mt19937 random(99);
  FrameDecoder decoder;
  for (int i = 0; i < 2000; ++i) {
    Bytes chunk(random() % 512);
    for (auto& byte : chunk) byte = static_cast<std::uint8_t>(random() % 4 == 0 ? 'L' : random());
    decoder.feed(chunk);
    drain(decoder);
    ASSERT_LE(decoder.buffered(), kHeaderSize + kMaxPayload + kTrailerSize);
  }
}

}  // namespace
}  // namespace lightstage::protocol
