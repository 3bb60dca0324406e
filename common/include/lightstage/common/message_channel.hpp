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
  explicit MessageChannel(std::unique_ptr<ByteLink> link);

  // Throws LinkClosed.
  void send(const google::protobuf::MessageLite& message);
  // Parses the next message into `message`; false after `timeout` without one.
  // Throws ProtocolError (bad frame or payload) and LinkClosed.
  bool receive(google::protobuf::MessageLite& message, std::chrono::milliseconds timeout);

  ByteLink& link() { return *link_; }

 private:
  std::unique_ptr<ByteLink> link_;
  protocol::FrameDecoder decoder_;
  std::mutex send_mutex_;
};

}  // namespace lightstage
