#include "lightstage/common/message_channel.hpp"

#include <fmt/format.h>

#include <array>
#include <string>

namespace lightstage {

MessageChannel::MessageChannel(std::unique_ptr<ByteLink> link,
                               std::chrono::milliseconds partial_frame_timeout)
    : link_(std::move(link)),
      partial_frame_timeout_(partial_frame_timeout),
      last_bytes_at_(std::chrono::steady_clock::now()) {}

void MessageChannel::send(const google::protobuf::MessageLite& message) {
  std::string bytes;
  if (!message.SerializeToString(&bytes)) throw ProtocolError("could not serialize a message");
  const auto frame =
      protocol::encode_frame(std::span(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()));
  const std::lock_guard lock(send_mutex_);
  link_->write(frame);
}

bool MessageChannel::receive(google::protobuf::MessageLite& message, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  std::array<std::uint8_t, 4096> chunk{};
  for (;;) {
    if (auto frame = decoder_.next()) {
      if (!frame->error.empty()) throw ProtocolError(fmt::format("{}: {}", link_->describe(), frame->error));
      message.Clear();
      if (!message.ParseFromArray(frame->payload.data(), static_cast<int>(frame->payload.size()))) {
        throw ProtocolError(fmt::format("{}: a frame of {} bytes is not a valid {}", link_->describe(),
                                        frame->payload.size(), message.GetTypeName()));
      }
      return true;
    }
    const auto now = std::chrono::steady_clock::now();
    // Nothing complete is buffered here, so whatever is buffered is a frame begun.
    if (decoder_.buffered() > 0 && now - last_bytes_at_ >= partial_frame_timeout_) {
      if (auto report = decoder_.abandon_partial()) {
        throw ProtocolError(fmt::format("{}: {}", link_->describe(), report->error));
      }
    }
    if (now >= deadline && timeout.count() > 0) return false;
    auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now);
    if (decoder_.buffered() > 0 && timeout.count() > 0) {
      // Wake in time to give up on the frame begun.
      left = std::min(left, std::chrono::duration_cast<std::chrono::milliseconds>(
                                last_bytes_at_ + partial_frame_timeout_ - now));
    }
    const std::size_t n = link_->read(chunk, std::max(left, std::chrono::milliseconds(0)));
    if (n == 0) {
      if (std::chrono::steady_clock::now() >= deadline) return false;
      continue;
    }
    last_bytes_at_ = std::chrono::steady_clock::now();
    bytes_received_ += n;
    decoder_.feed(std::span(chunk.data(), n));
  }
}

}  // namespace lightstage
