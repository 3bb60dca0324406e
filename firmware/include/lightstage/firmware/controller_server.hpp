#pragma once
// The controller side of controller.proto: serves one host at a time over a
// MessageChannel and turns its requests into Controller calls.
//
// - A client opens with Hello; any other request before it gets
//   Error{NOT_NEGOTIATED}, a Hello whose version range does not overlap ours
//   Error{VERSION_MISMATCH}. Hello is answered with Info.
// - Every request with a request_id gets exactly one reply (Ack, Status,
//   Info or Error) carrying that id; a Heartbeat with request_id 0 gets none.
// - Unsolicited messages (request_id 0): StepEvent, SequenceDone, Fault.
// - A malformed frame or payload is answered with Error{MALFORMED_FRAME} and
//   the connection keeps being served.
// - One controlling client at a time: a connection arriving while one is
//   served gets Error{BUSY} (naming the host in control and since when) and
//   is closed.
// - A valid message is a CRC-checked frame holding a HostMessage with a body;
//   garbage, damaged frames and empty messages are answered but prove nothing.
// - Watchdog: while LEDs are lit or a sequence runs, a gap of more than the
//   negotiated timeout between valid messages from the host aborts everything
//   and darkens the dome (WATCHDOG). A lost link does the same (LINK_LOST),
//   and so does leaving serve() (SHUTDOWN).
// - Lease: a connection that has not negotiated within hello_timeout, or a
//   negotiated host that sends no valid message for idle_lease (at least its
//   watchdog timeout), gets Error{SESSION_EXPIRED}, the dome goes dark and
//   the connection is closed, so that a silent or trickling peer cannot hold
//   the one-host lock. The hello timeout applies to a connection that has
//   sent something, or that another host has been refused for: a serial line
//   or USB function with no host on it stays open quietly.
// - A failed GPIO backend ends serving: the host is told (Fault, Status
//   FAULT) and serve() returns; lightstage-domed then exits non-zero.

#include "lightstage/common/link.hpp"
#include "lightstage/common/message_channel.hpp"
#include "lightstage/firmware/controller.hpp"
#include "lightstage/proto/controller.pb.h"

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

namespace lightstage::firmware {

inline constexpr std::uint32_t kProtocolVersion = 1;     // newest we speak
inline constexpr std::uint32_t kMinProtocolVersion = 1;  // oldest we accept

struct ServerOptions {
  std::uint32_t default_watchdog_ms = 1000;  // when Hello asks for 0
  std::uint32_t min_watchdog_ms = 20;
  std::uint32_t max_watchdog_ms = 60'000;
  std::string gpio_uri;  // reported in Info
  std::chrono::milliseconds hello_timeout{5000};
  std::chrono::milliseconds idle_lease{30'000};
};

class ControllerServer {
 public:
  // How often the serve loop looks at the watchdog, the stop flag and new connections.
  static constexpr std::chrono::milliseconds kPoll{5};

  ControllerServer(Controller& controller, ServerOptions options);

  // Accepts and serves clients until `stop` is set; then stops the controller
  // (SHUTDOWN: every LED dark) and returns.
  void serve(LinkListener& listener, const std::atomic<bool>& stop);

  // Serves one connected client until it disconnects or `stop` is set. With a
  // listener, connections arriving meanwhile are refused with BUSY.
  void serve_client(std::unique_ptr<ByteLink> link, const std::atomic<bool>& stop,
                    LinkListener* listener = nullptr);

 private:
  struct Session {
    std::string peer;
    bool negotiated = false;
    bool contested = false;  // another host was refused while this one held the dome
    std::uint32_t version = 0;
    std::uint32_t watchdog_ms = 0;
    std::chrono::steady_clock::time_point connected;
    std::chrono::system_clock::time_point connected_wall;  // for BUSY: since when
    std::chrono::steady_clock::time_point last_message;    // the last valid one
  };

  // The reply to `request`; nullopt when none is due (heartbeat without id, or already sent).
  std::optional<proto::ControllerMessage> handle(const proto::HostMessage& request, Session& session,
                                                 MessageChannel& channel);
  proto::ControllerMessage info(const Session& session) const;
  void refuse_extra_client(LinkListener& listener, Session& holder);
  // Why the session has run out (no Hello in time, idle past its lease), or nullopt.
  std::optional<std::string> expired(const Session& session, const MessageChannel& channel,
                                     std::chrono::steady_clock::time_point now) const;

  Controller& controller_;
  ServerOptions options_;
};

// An Error message with `request_id`.
proto::ControllerMessage error_reply(std::uint32_t request_id, proto::Error::Code code,
                                     const std::string& message);

}  // namespace lightstage::firmware
