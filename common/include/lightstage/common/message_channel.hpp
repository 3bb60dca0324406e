#pragma once
// Protobuf messages over a ByteLink, one message per frame (framing.hpp).
// send() may be called from several threads; receive() from one.

#include "lightstage/common/error.hpp"
#include "lightstage/common/framing.hpp"
#include "lightstage/common/link.hpp"

#include <google/protobuf/message_lite.h>

#include <chrono>
#include <memory>
#include <mutex>

namespace lightstage {

// A frame was damaged or its payload is not the expected message. The
// channel has skipped it and stays usable: answer with an error and go on.
class ProtocolError : public Error {
 public:
  using Error::Error;
};

class MessageChannel {
 public:
  // A frame begun but not finished is given up after this long without a
  // byte, so a peer that stops mid-frame costs a bounded wait, not the
  // arrival of the rest of a frame that will never come.
  static constexpr std::chrono::milliseconds kPartialFrameTimeout{1000};

  explicit MessageChannel(std::unique_ptr<ByteLink> link,
                          std::chrono::milliseconds partial_frame_timeout = kPartialFrameTimeout);

  // Throws LinkClosed.
  void send(const google::protobuf::MessageLite& message);
  // Parses the next message into `message`; false after `timeout` without one.
  // Throws ProtocolError (bad frame or payload, a frame abandoned mid-way)
  // and LinkClosed.
  bool receive(google::protobuf::MessageLite& message, std::chrono::milliseconds timeout);

  ByteLink& link() { return *link_; }
  // Every byte read from the link so far, framed or not.
  std::uint64_t bytes_received() const { return bytes_received_; }

 private:
  std::unique_ptr<ByteLink> link_;
  protocol::FrameDecoder decoder_;
  std::chrono::milliseconds partial_frame_timeout_;
  std::chrono::steady_clock::time_point last_bytes_at_;
  std::uint64_t bytes_received_ = 0;
  std::mutex send_mutex_;
};

}  // namespace lightstage
