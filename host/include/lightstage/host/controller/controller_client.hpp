#pragma once
// The host's side of the controller protocol (common/proto/.../controller.proto):
// connects, negotiates the version, keeps the controller's watchdog fed with
// heartbeats, sends commands and waits for their replies, and hands the
// controller's unsolicited step events to whoever runs a sequence.
//
// Threads: a reader thread demultiplexes replies (by request id) from events;
// a heartbeat thread sends a Heartbeat every `heartbeat_period`. Requests may
// come from several threads at once, each waiting for its own reply (an
// abort() or all_off() from another thread ends a run_sequence() early); one
// thread at a time runs a sequence, as its events go to that one caller.

#include "lightstage/common/error.hpp"
#include "lightstage/common/link.hpp"
#include "lightstage/proto/controller.pb.h"

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace lightstage {

class MessageChannel;

// The controller answered with an Error, or did not answer in time.
class ControllerError : public Error {
 public:
  ControllerError(proto::Error::Code code, const std::string& message) : Error(message), code_(code) {}
  proto::Error::Code code() const { return code_; }

 private:
  proto::Error::Code code_;
};

inline constexpr std::uint32_t kProtocolVersion = 1;

struct ControllerClientOptions {
  std::string client_name = "lightstage";
  std::chrono::milliseconds reply_timeout{3000};
  std::chrono::milliseconds heartbeat_period{200};
  // Asked of the controller in Hello; 0 = its default. It clamps to its maximum.
  std::uint32_t watchdog_timeout_ms = 0;
  // Test hook: no heartbeats at all (the watchdog then fires).
  bool send_heartbeats = true;
};

// What a sequence run produced: one event per step that ran, and the end.
struct SequenceRun {
  std::vector<proto::StepEvent> steps;
  proto::SequenceDone done;
  bool ok() const { return done.outcome() == proto::OK; }
};

class ControllerClient {
 public:
  // Takes a connected link and negotiates (throws ControllerError / LinkClosed).
  ControllerClient(std::unique_ptr<ByteLink> link, ControllerClientOptions options = {});
  ~ControllerClient();
  ControllerClient(const ControllerClient&) = delete;
  ControllerClient& operator=(const ControllerClient&) = delete;

  const proto::Info& info() const { return info_; }

  // Lights exactly these LEDs (id, level); every other LED goes dark.
  void set_leds(const std::vector<std::pair<std::uint32_t, float>>& leds);
  void all_off() { set_leds({}); }
  void upload(const proto::Sequence& sequence);
  void start(std::uint32_t sequence_id, std::int64_t start_ns = 0);
  void abort();
  proto::Status status();

  // Uploads, starts and waits for the SequenceDone of `sequence`, calling
  // `on_step` for every StepEvent as it arrives. Throws LinkClosed when the
  // link drops, ControllerError when the run does not end within `timeout`.
  SequenceRun run_sequence(const proto::Sequence& sequence,
                           const std::function<void(const proto::StepEvent&)>& on_step = {},
                           std::chrono::milliseconds timeout = std::chrono::minutes(10));

  // Stops heartbeats (the controller's watchdog then darkens the dome), for tests.
  void stop_heartbeats();
  // Closes the link at once.
  void disconnect();

 private:
  proto::ControllerMessage request(proto::HostMessage message);
  void read_loop();
  void heartbeat_loop();
  std::optional<proto::ControllerMessage> next_event(std::chrono::steady_clock::time_point deadline);
  // After the link failed (mutex_ held): the controller's refusal as a
  // ControllerError when it sent one, else LinkClosed.
  [[noreturn]] void throw_link_failure() const;

  ControllerClientOptions options_;
  std::unique_ptr<MessageChannel> channel_;
  proto::Info info_;

  std::mutex mutex_;
  std::condition_variable changed_;
  std::uint32_t next_request_id_ = 1;
  std::map<std::uint32_t, proto::ControllerMessage> replies_;
  std::deque<proto::ControllerMessage> events_;
  std::string link_error_;  // set when the reader stops: why
  // An Error the controller sent unasked (request id 0) as its last message,
  // e.g. BUSY before it hangs up on a second host: when the link then closes,
  // the reason a request fails, rather than the hang-up itself.
  std::optional<proto::Error> refusal_;
  bool stopping_ = false;
  bool heartbeats_ = true;

  std::thread reader_;
  std::thread heartbeat_;
};

// Connects to a controller by URI (tcp:, unix:, serial:, usb:) and negotiates.
std::unique_ptr<ControllerClient> connect_controller(const std::string& uri,
                                                     ControllerClientOptions options = {});

// Lateness figures over the steps of a run (ns).
struct LatenessStats {
  std::size_t steps = 0;
  double median_ns = 0, p99_ns = 0, max_ns = 0;
};
LatenessStats lateness_stats(const std::vector<proto::StepEvent>& steps);

}  // namespace lightstage
