#include "lightstage/sim/gpio/sim_chip.hpp"

#include "lightstage/common/clock.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/common/message_channel.hpp"
#include "lightstage/common/socket_link.hpp"
#include "lightstage/proto/sim_gpio.pb.h"

#include <fmt/format.h>

#include <atomic>
#include <condition_variable>
#include <deque>
#include <map>
#include <mutex>
#include <set>
#include <thread>

namespace lightstage::sim::gpio {
namespace {

namespace pb = lightstage::proto::sim;
using lightstage::gpio::EdgeEvent;
using lightstage::gpio::GpioError;

// How long a request waits for the sim's answer before the sim counts as gone.
constexpr std::chrono::milliseconds kAnswerTimeout(5000);

std::string socket_uri(const std::string& address) {
  if (address.starts_with("sim:")) return socket_uri(address.substr(4));
  if (address.starts_with("unix:") || address.starts_with("tcp:")) return address;
  return "unix:" + address;
}

// One connection to the sim, shared by the chip and the lines it handed out.
// A reader thread sorts what arrives: answers to waiting calls, errors for
// pipelined sets, and edges into per-line queues.
class SimConnection {
 public:
  SimConnection(std::unique_ptr<ByteLink> link, std::string uri)
      : channel_(std::move(link)), uri_(std::move(uri)), reader_([this] { read_loop(); }) {}

  ~SimConnection() {
    // One round trip first: the sim answers only after applying every set
    // sent before, so the last changes (all LEDs off on exit) are recorded
    // even on links that drop unread data at close.
    try {
      round_trip(std::chrono::seconds(1));
    } catch (const std::exception&) {
      // Gone already: nothing more to flush.
    }
    stopping_ = true;
    channel_.link().shutdown();
    reader_.join();
  }
  SimConnection(const SimConnection&) = delete;
  SimConnection& operator=(const SimConnection&) = delete;

  const std::string& uri() const { return uri_; }

  // Sends and waits for the answer; an Error answer becomes GpioError.
  pb::ServerMessage call(pb::ClientMessage& message, std::chrono::milliseconds timeout = kAnswerTimeout) {
    std::unique_lock lock(mutex_);
    throw_if_failed(lock);
    const std::uint32_t id = next_id_++;
    awaited_.insert(id);
    message.set_request_id(id);
    lock.unlock();
    send(message);
    lock.lock();
    const bool answered =
        cv_.wait_for(lock, timeout, [&] { return replies_.contains(id) || !closed_.empty(); });
    awaited_.erase(id);
    if (!answered)
      throw GpioError(
          fmt::format("{}: lightstage-sim did not answer within {} s", uri_, timeout.count() / 1000.0));
    const auto it = replies_.find(id);
    if (it == replies_.end()) throw GpioError(closed_);
    pb::ServerMessage reply = std::move(it->second);
    replies_.erase(it);
    if (reply.has_error()) throw GpioError(fmt::format("{}: {}", uri_, reply.error().message()));
    return reply;
  }

  // A request answered only after the sim has applied everything sent before and sent every
  // edge due by the time it reads it.
  void round_trip(std::chrono::milliseconds timeout = kAnswerTimeout) {
    pb::ClientMessage sync;
    sync.mutable_chip_info();
    call(sync, timeout);
  }

  // Sends without waiting; a later error answer is thrown by the next call.
  void post(pb::ClientMessage& message) {
    std::unique_lock lock(mutex_);
    throw_if_failed(lock);
    message.set_request_id(next_id_++);
    lock.unlock();
    send(message);
  }

  void watch(unsigned offset) {
    const std::lock_guard lock(mutex_);
    edges_[offset].clear();
  }
  void unwatch(unsigned offset) {
    const std::lock_guard lock(mutex_);
    edges_.erase(offset);
  }
  void drain(unsigned offset) {
    const std::lock_guard lock(mutex_);
    edges_[offset].clear();
  }

  std::optional<EdgeEvent> wait_edge(unsigned offset, std::int64_t deadline_ns) {
    std::unique_lock lock(mutex_);
    const auto deadline = std::chrono::steady_clock::time_point(std::chrono::nanoseconds(deadline_ns));
    for (;;) {
      throw_if_failed(lock);
      auto& queue = edges_[offset];
      if (!queue.empty()) {
        const EdgeEvent edge = queue.front();
        queue.pop_front();
        return edge;
      }
      if (monotonic_now_ns() >= deadline_ns) return std::nullopt;
      cv_.wait_until(lock, deadline);
    }
  }

 private:
  void send(const pb::ClientMessage& message) {
    try {
      channel_.send(message);
    } catch (const LinkClosed& e) {
      mark_closed(e.what());
      throw GpioError(fmt::format("{}: lightstage-sim connection lost: {}", uri_, e.what()));
    }
  }

  // Throws for a lost connection (always) or a pending error from a pipelined set (once).
  void throw_if_failed(std::unique_lock<std::mutex>& /*held*/) {
    if (!closed_.empty()) throw GpioError(closed_);
    if (!pending_error_.empty()) {
      std::string error = std::move(pending_error_);
      pending_error_.clear();
      throw GpioError(fmt::format("{}: {}", uri_, error));
    }
  }

  void mark_closed(const std::string& why) {
    {
      const std::lock_guard lock(mutex_);
      if (closed_.empty()) closed_ = fmt::format("{}: lightstage-sim connection lost: {}", uri_, why);
    }
    cv_.notify_all();
  }

  void read_loop() {
    while (!stopping_) {
      pb::ServerMessage message;
      try {
        if (!channel_.receive(message, std::chrono::milliseconds(200))) continue;
      } catch (const ProtocolError& e) {
        logger("gpio")->warn("{}: bad frame from lightstage-sim: {}", uri_, e.what());
        continue;
      } catch (const LinkClosed& e) {
        mark_closed(stopping_ ? "closed" : e.what());
        return;
      }
      dispatch(std::move(message));
    }
  }

  void dispatch(pb::ServerMessage message) {
    {
      const std::lock_guard lock(mutex_);
      const std::uint32_t id = message.request_id();
      if (id == 0 && message.has_edge()) {
        const auto& edge = message.edge();
        const auto queue = edges_.find(edge.offset());
        if (queue != edges_.end()) queue->second.push_back({edge.offset(), edge.rising(), edge.t_ns()});
      } else if (awaited_.contains(id)) {
        replies_[id] = std::move(message);
      } else if (message.has_error() && pending_error_.empty()) {
        pending_error_ = message.error().message();  // a pipelined set failed, or a frame was bad
      }
    }
    cv_.notify_all();
  }

  MessageChannel channel_;
  const std::string uri_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::map<std::uint32_t, pb::ServerMessage> replies_;
  std::set<std::uint32_t> awaited_;
  std::map<unsigned, std::deque<EdgeEvent>> edges_;
  std::string pending_error_;
  std::string closed_;  // non-empty once the connection is gone: the message to throw
  std::uint32_t next_id_ = 1;
  std::atomic<bool> stopping_{false};
  std::thread reader_;  // last: starts once everything above exists
};

class SimOutputLines final : public lightstage::gpio::OutputLines {
 public:
  SimOutputLines(std::shared_ptr<SimConnection> connection, std::vector<unsigned> offsets)
      : connection_(std::move(connection)), offsets_(std::move(offsets)) {}

  ~SimOutputLines() override {
    try {
      pb::ClientMessage message;
      for (const unsigned offset : offsets_) message.mutable_release_lines()->add_offsets(offset);
      connection_->post(message);
    } catch (const GpioError&) {
      // The connection is gone, and the sim released the lines with it.
    }
  }
  SimOutputLines(const SimOutputLines&) = delete;
  SimOutputLines& operator=(const SimOutputLines&) = delete;

  void set(std::span<const int> values, std::int64_t t_ns) override {
    if (values.size() != offsets_.size()) {
      throw GpioError(fmt::format("{}: {} values for {} output lines", connection_->uri(), values.size(),
                                  offsets_.size()));
    }
    pb::ClientMessage message;
    auto* set = message.mutable_set_values();
    for (std::size_t i = 0; i < values.size(); ++i) {
      set->add_offsets(offsets_[i]);
      set->add_values(values[i] != 0 ? 1 : 0);
    }
    set->set_t_ns(t_ns);
    connection_->post(message);
  }

  std::size_t size() const override { return offsets_.size(); }

 private:
  std::shared_ptr<SimConnection> connection_;
  std::vector<unsigned> offsets_;
};

class SimEdgeInput final : public lightstage::gpio::EdgeInput {
 public:
  SimEdgeInput(std::shared_ptr<SimConnection> connection, unsigned offset)
      : connection_(std::move(connection)), offset_(offset) {}

  ~SimEdgeInput() override {
    connection_->unwatch(offset_);
    try {
      pb::ClientMessage message;
      message.mutable_release_lines()->add_offsets(offset_);
      connection_->post(message);
    } catch (const GpioError&) {
    }
  }
  SimEdgeInput(const SimEdgeInput&) = delete;
  SimEdgeInput& operator=(const SimEdgeInput&) = delete;

  std::optional<EdgeEvent> wait_until(std::int64_t deadline_ns) override {
    return connection_->wait_edge(offset_, deadline_ns);
  }
  void drain() override { connection_->drain(offset_); }
  void catch_up() override { connection_->round_trip(); }

 private:
  std::shared_ptr<SimConnection> connection_;
  unsigned offset_;
};

class SimChip final : public lightstage::gpio::Chip {
 public:
  explicit SimChip(std::shared_ptr<SimConnection> connection) : connection_(std::move(connection)) {}

  lightstage::gpio::ChipInfo info() const override {
    pb::ClientMessage message;
    message.mutable_chip_info();
    const pb::ServerMessage reply = connection_->call(message);
    if (!reply.has_chip_info())
      throw GpioError(connection_->uri() + ": lightstage-sim answered chip info oddly");
    lightstage::gpio::ChipInfo info;
    info.label = reply.chip_info().label();
    info.line_names.assign(reply.chip_info().line_names().begin(), reply.chip_info().line_names().end());
    info.consumers.assign(reply.chip_info().line_consumers().begin(),
                          reply.chip_info().line_consumers().end());
    info.consumers.resize(info.line_names.size());
    return info;
  }

  std::unique_ptr<lightstage::gpio::OutputLines> request_outputs(std::span<const unsigned> offsets,
                                                                 std::span<const bool> active_low,
                                                                 std::span<const int> initial,
                                                                 const std::string& consumer) override {
    pb::ClientMessage message;
    auto* request = message.mutable_request_lines();
    request->set_output(true);
    request->set_consumer(consumer);
    for (const unsigned offset : offsets) request->add_offsets(offset);
    for (const bool low : active_low) request->add_active_low(low);
    for (const int value : initial) request->add_initial_values(value != 0 ? 1 : 0);
    request->set_t_ns(monotonic_now_ns());
    connection_->call(message);
    return std::make_unique<SimOutputLines>(connection_,
                                            std::vector<unsigned>(offsets.begin(), offsets.end()));
  }

  std::unique_ptr<lightstage::gpio::EdgeInput> request_edges(unsigned offset, bool active_low,
                                                             const std::string& consumer) override {
    pb::ClientMessage message;
    auto* request = message.mutable_request_lines();
    request->set_output(false);
    request->set_consumer(consumer);
    request->add_offsets(offset);
    request->add_active_low(active_low);
    connection_->watch(offset);  // before the request, so no edge is missed
    try {
      connection_->call(message);
    } catch (...) {
      connection_->unwatch(offset);
      throw;
    }
    return std::make_unique<SimEdgeInput>(connection_, offset);
  }

 private:
  std::shared_ptr<SimConnection> connection_;
};

std::shared_ptr<SimConnection> open_connection(const std::string& address,
                                               std::chrono::milliseconds timeout) {
  const std::string uri = socket_uri(address);
  try {
    return std::make_shared<SimConnection>(connect_socket_link(uri, timeout), uri);
  } catch (const Error& e) {
    throw GpioError(fmt::format("sim: cannot reach lightstage-sim at {}: {}", uri, e.what()));
  }
}

}  // namespace

std::unique_ptr<lightstage::gpio::Chip> connect_sim_chip(const std::string& address,
                                                         std::chrono::milliseconds connect_timeout) {
  return std::make_unique<SimChip>(open_connection(address, connect_timeout));
}

void inject_sim_fault(const std::string& address, const std::string& fault) {
  const auto connection = open_connection(address, std::chrono::milliseconds(2000));
  pb::ClientMessage message;
  message.mutable_inject_fault()->set_spec(fault);
  connection->call(message);
}

}  // namespace lightstage::sim::gpio
