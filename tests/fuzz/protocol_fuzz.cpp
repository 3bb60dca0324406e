// The wire protocol faces whatever arrives on a link. Any bytes, in any split,
// must give frames or reports of dropped bytes from the decoder, and messages
// or ProtocolErrors from a channel, never a crash, a hang or unbounded memory.
// Every frame is parsed as each message type that travels on our links, and
// what parses must survive serialize -> parse unchanged; every payload must
// survive encode_frame -> FrameDecoder unchanged.
#include "chunked_link.hpp"
#include "lightstage/common/framing.hpp"
#include "lightstage/common/message_channel.hpp"
#include "lightstage/proto/controller.pb.h"
#include "lightstage/proto/sim_gpio.pb.h"

#include <google/protobuf/stubs/logging.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <deque>
#include <span>
#include <string>
#include <vector>

namespace {

using lightstage::protocol::FrameDecoder;
using Bytes = std::vector<std::uint8_t>;

void require(bool condition) {
  if (!condition) std::abort();
}

template <typename Message>
void check_message(const Bytes& payload) {
  Message message;
  if (!message.ParseFromArray(payload.data(), static_cast<int>(payload.size()))) return;
  const std::string once = message.SerializeAsString();
  Message again;
  require(again.ParseFromString(once));
  require(again.SerializeAsString() == once);
}

void check_payload(const Bytes& payload) {
  check_message<lightstage::proto::HostMessage>(payload);
  check_message<lightstage::proto::ControllerMessage>(payload);
  check_message<lightstage::proto::sim::ClientMessage>(payload);
  check_message<lightstage::proto::sim::ServerMessage>(payload);
  // encode -> decode gives the payload back, alone and whole.
  FrameDecoder decoder;
  decoder.feed(lightstage::protocol::encode_frame(payload));
  const auto frame = decoder.next();
  require(frame && frame->error.empty() && frame->payload == payload);
  require(!decoder.next() && decoder.buffered() == 0);
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  // Protobuf logs every string field that is not UTF-8; that is expected here.
  google::protobuf::SetLogHandler(nullptr);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  // The first byte picks the chunking; the rest is the byte stream.
  const std::size_t chunk_size = 1 + data[0] % 64;
  const std::span<const std::uint8_t> stream(data + 1, size - 1);

  // The decoder, fed chunk by chunk.
  FrameDecoder decoder;
  std::size_t framed = 0;
  std::size_t frames = 0;
  std::size_t reports = 0;
  std::deque<Bytes> chunks;
  for (std::size_t at = 0; at < stream.size(); at += chunk_size) {
    const auto chunk = stream.subspan(at, std::min(chunk_size, stream.size() - at));
    chunks.emplace_back(chunk.begin(), chunk.end());
    decoder.feed(chunk);
    while (auto frame = decoder.next()) {
      if (frame->error.empty()) {
        ++frames;
        framed +=
            lightstage::protocol::kHeaderSize + frame->payload.size() + lightstage::protocol::kTrailerSize;
        check_payload(frame->payload);
      } else {
        ++reports;
        require(!frame->payload.size());
      }
    }
    require(decoder.buffered() <= lightstage::protocol::kHeaderSize + lightstage::protocol::kMaxPayload +
                                      lightstage::protocol::kTrailerSize);
  }
  // Frames never invent bytes; two reports never come back to back without a
  // frame or more input between them (one report per run of bad bytes).
  require(framed + decoder.buffered() <= stream.size());
  require(reports <= frames + (stream.size() + chunk_size - 1) / chunk_size);

  // The channel over the same chunks: messages or ProtocolErrors, then LinkClosed.
  lightstage::MessageChannel channel(std::make_unique<lightstage::fuzz::ChunkedLink>(std::move(chunks)));
  std::size_t received = 0;
  for (;;) {
    try {
      lightstage::proto::HostMessage message;
      if (channel.receive(message, std::chrono::milliseconds(0))) ++received;
    } catch (const lightstage::ProtocolError&) {
    } catch (const lightstage::LinkClosed&) {
      break;
    }
  }
  require(received <= frames);
  return 0;
}
