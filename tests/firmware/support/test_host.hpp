#pragma once
// The host end of controller.proto for server tests: numbered requests, the
// reply with the same number, and every unsolicited message kept in order.

#include "lightstage/common/message_channel.hpp"
#include "lightstage/proto/controller.pb.h"

#include <gtest/gtest.h>

#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

namespace lightstage::firmware::testing {

class TestHost {
 public:
  explicit TestHost(std::unique_ptr<ByteLink> link) : channel_(std::move(link)) {}

  // Sends `request` with the next request id and returns the reply to it.
  // Fails the test (and returns an empty message) after `timeout`.
  proto::ControllerMessage request(proto::HostMessage request,
                                   std::chrono::milliseconds timeout = std::chrono::seconds(10)) {
    request.set_request_id(++last_id_);
    channel_.send(request);
    return wait_reply(last_id_, timeout);
  }

  proto::ControllerMessage hello(std::uint32_t watchdog_ms = 0, std::uint32_t version = 1,
                                 std::uint32_t min_version = 1) {
    proto::HostMessage message;
    message.mutable_hello()->set_protocol_version(version);
    message.mutable_hello()->set_min_protocol_version(min_version);
    message.mutable_hello()->set_client("firmware unit test");
    message.mutable_hello()->set_watchdog_timeout_ms(watchdog_ms);
    return request(message);
  }

  void send_raw(std::span<const std::uint8_t> bytes) { channel_.link().write(bytes); }
  void send(const proto::HostMessage& message) { channel_.send(message); }

  proto::ControllerMessage wait_reply(std::uint32_t id, std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      proto::ControllerMessage message;
      if (!channel_.receive(message, std::chrono::milliseconds(20))) continue;
      if (message.request_id() == id && !is_unsolicited(message)) return message;
      unsolicited_.push_back(message);
    }
    ADD_FAILURE() << "no reply to request " << id;
    return {};
  }

  // Waits until an unsolicited message satisfies `match` (kept in unsolicited()).
  std::optional<proto::ControllerMessage> wait_for(
      const std::function<bool(const proto::ControllerMessage&)>& match,
      std::chrono::milliseconds timeout = std::chrono::seconds(10)) {
    for (const auto& message : unsolicited_) {
      if (match(message)) return message;
    }
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      proto::ControllerMessage message;
      if (!channel_.receive(message, std::chrono::milliseconds(20))) continue;
      unsolicited_.push_back(message);
      if (match(message)) return message;
    }
    return std::nullopt;
  }

  const std::vector<proto::ControllerMessage>& unsolicited() const { return unsolicited_; }
  MessageChannel& channel() { return channel_; }

 private:
  static bool is_unsolicited(const proto::ControllerMessage& message) {
    return message.has_step_event() || message.has_sequence_done() || message.has_fault();
  }

  MessageChannel channel_;
  std::uint32_t last_id_ = 0;
  std::vector<proto::ControllerMessage> unsolicited_;
};

}  // namespace lightstage::firmware::testing
