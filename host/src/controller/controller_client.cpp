#include "lightstage/host/controller/controller_client.hpp"

#include "lightstage/common/log.hpp"
#include "lightstage/common/message_channel.hpp"
#include "lightstage/common/version.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace lightstage {
namespace {

constexpr auto kPoll = std::chrono::milliseconds(50);

std::string body_name(const proto::ControllerMessage& m) {
  const auto* field = proto::ControllerMessage::descriptor()->FindFieldByNumber(m.body_case());
  return field ? field->name() : "nothing";
}

}  // namespace

ControllerClient::ControllerClient(std::unique_ptr<ByteLink> link, ControllerClientOptions options)
    : options_(std::move(options)), channel_(std::make_unique<MessageChannel>(std::move(link))) {
  heartbeats_ = options_.send_heartbeats;
  reader_ = std::thread([this] { read_loop(); });
  try {
    proto::HostMessage hello;
    hello.mutable_hello()->set_protocol_version(kProtocolVersion);
    hello.mutable_hello()->set_min_protocol_version(kProtocolVersion);
    hello.mutable_hello()->set_client(fmt::format("{} {}", options_.client_name, kVersion));
    hello.mutable_hello()->set_watchdog_timeout_ms(options_.watchdog_timeout_ms);
    const proto::ControllerMessage reply = request(std::move(hello));
    if (!reply.has_info()) {
      throw ControllerError(
          proto::Error::UNKNOWN,
          fmt::format("{}: answered Hello with {}", channel_->link().describe(), body_name(reply)));
    }
    info_ = reply.info();
  } catch (...) {
    disconnect();
    throw;
  }
  heartbeat_ = std::thread([this] { heartbeat_loop(); });
}

ControllerClient::~ControllerClient() { disconnect(); }

void ControllerClient::disconnect() {
  {
    const std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  channel_->link().shutdown();
  if (reader_.joinable() && reader_.get_id() != std::this_thread::get_id()) reader_.join();
  if (heartbeat_.joinable() && heartbeat_.get_id() != std::this_thread::get_id()) heartbeat_.join();
}

void ControllerClient::stop_heartbeats() {
  const std::lock_guard lock(mutex_);
  heartbeats_ = false;
}

void ControllerClient::read_loop() {
  for (;;) {
    proto::ControllerMessage message;
    try {
      if (!channel_->receive(message, kPoll)) {
        const std::lock_guard lock(mutex_);
        if (stopping_) return;
        continue;
      }
    } catch (const ProtocolError& e) {
      logger("controller")->warn("{}", e.what());  // skipped; the link goes on
      continue;
    } catch (const LinkClosed& e) {
      const std::lock_guard lock(mutex_);
      link_error_ = e.what();
      changed_.notify_all();
      return;
    }
    const std::lock_guard lock(mutex_);
    // Only an error that is the last thing the controller said explains a hang-up.
    if (message.request_id() == 0 && message.has_error()) {
      refusal_ = message.error();
    } else {
      refusal_.reset();
    }
    if (message.request_id() != 0) {
      replies_[message.request_id()] = std::move(message);
    } else {
      events_.push_back(std::move(message));
    }
    changed_.notify_all();
  }
}

void ControllerClient::heartbeat_loop() {
  std::uint64_t counter = 0;
  std::unique_lock lock(mutex_);
  while (!stopping_ && link_error_.empty()) {
    if (heartbeats_) {
      proto::HostMessage beat;
      beat.mutable_heartbeat()->set_counter(++counter);
      lock.unlock();
      try {
        channel_->send(beat);
      } catch (const LinkClosed&) {
        return;  // the reader reports it
      }
      lock.lock();
    }
    changed_.wait_for(lock, options_.heartbeat_period, [this] { return stopping_ || !link_error_.empty(); });
  }
}

void ControllerClient::throw_link_failure() const {
  if (refusal_) {
    throw ControllerError(refusal_->code(), fmt::format("controller: {} ({})", refusal_->message(),
                                                        proto::Error::Code_Name(refusal_->code())));
  }
  throw LinkClosed(link_error_);
}

proto::ControllerMessage ControllerClient::request(proto::HostMessage message) {
  std::unique_lock lock(mutex_);
  if (!link_error_.empty()) throw_link_failure();
  const std::uint32_t id = next_request_id_++;
  message.set_request_id(id);
  lock.unlock();
  try {
    channel_->send(message);
  } catch (const LinkClosed&) {
    // The controller may have refused and hung up first: let the reader take what it sent.
    lock.lock();
    changed_.wait_for(lock, options_.reply_timeout, [this] { return !link_error_.empty() || stopping_; });
    if (refusal_ || !link_error_.empty()) throw_link_failure();
    throw;
  }
  lock.lock();
  const bool answered = changed_.wait_for(lock, options_.reply_timeout, [&] {
    return replies_.count(id) > 0 || !link_error_.empty() || stopping_;
  });
  if (replies_.count(id) == 0) {
    if (!link_error_.empty()) throw_link_failure();
    throw ControllerError(proto::Error::UNKNOWN,
                          answered ? "disconnected"
                                   : fmt::format("{}: no reply within {} ms", channel_->link().describe(),
                                                 options_.reply_timeout.count()));
  }
  proto::ControllerMessage reply = std::move(replies_[id]);
  replies_.erase(id);
  if (reply.has_error()) {
    throw ControllerError(reply.error().code(), fmt::format("controller: {} ({})", reply.error().message(),
                                                            proto::Error::Code_Name(reply.error().code())));
  }
  return reply;
}

void ControllerClient::set_leds(const std::vector<std::pair<std::uint32_t, float>>& leds) {
  proto::HostMessage m;
  auto* set = m.mutable_set_leds();
  for (const auto& [id, level] : leds) {
    auto* led = set->add_leds();
    led->set_led_id(id);
    led->set_level(level);
  }
  request(std::move(m));
}

void ControllerClient::upload(const proto::Sequence& sequence) {
  proto::HostMessage m;
  *m.mutable_upload()->mutable_sequence() = sequence;
  request(std::move(m));
}

void ControllerClient::start(std::uint32_t sequence_id, std::int64_t start_ns) {
  proto::HostMessage m;
  m.mutable_run()->set_sequence_id(sequence_id);
  m.mutable_run()->set_start_ns(start_ns);
  request(std::move(m));
}

void ControllerClient::abort() {
  proto::HostMessage m;
  m.mutable_abort();
  request(std::move(m));
}

proto::Status ControllerClient::status() {
  proto::HostMessage m;
  m.mutable_status();
  const proto::ControllerMessage reply = request(std::move(m));
  if (!reply.has_status()) {
    throw ControllerError(proto::Error::UNKNOWN,
                          fmt::format("controller answered Status with {}", body_name(reply)));
  }
  return reply.status();
}

std::optional<proto::ControllerMessage> ControllerClient::next_event(
    std::chrono::steady_clock::time_point deadline) {
  std::unique_lock lock(mutex_);
  changed_.wait_until(lock, deadline,
                      [this] { return !events_.empty() || !link_error_.empty() || stopping_; });
  if (!events_.empty()) {
    proto::ControllerMessage event = std::move(events_.front());
    events_.pop_front();
    return event;
  }
  if (!link_error_.empty()) throw_link_failure();
  return std::nullopt;
}

SequenceRun ControllerClient::run_sequence(const proto::Sequence& sequence,
                                           const std::function<void(const proto::StepEvent&)>& on_step,
                                           std::chrono::milliseconds timeout) {
  {
    // Events of an earlier run are stale now.
    const std::lock_guard lock(mutex_);
    events_.clear();
  }
  upload(sequence);
  start(sequence.id());
  SequenceRun run;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const auto event = next_event(deadline);
    if (!event) {
      throw ControllerError(proto::Error::UNKNOWN, fmt::format("sequence {} did not finish within {} s",
                                                               sequence.id(), timeout.count() / 1000.0));
    }
    if (event->has_step_event() && event->step_event().sequence_id() == sequence.id()) {
      run.steps.push_back(event->step_event());
      if (on_step) on_step(event->step_event());
    } else if (event->has_sequence_done() && event->sequence_done().sequence_id() == sequence.id()) {
      run.done = event->sequence_done();
      return run;
    }
  }
}

LatenessStats lateness_stats(const std::vector<proto::StepEvent>& steps) {
  LatenessStats stats;
  std::vector<double> values;
  for (const auto& step : steps) values.push_back(static_cast<double>(step.lateness_ns()));
  stats.steps = values.size();
  if (values.empty()) return stats;
  std::sort(values.begin(), values.end());
  const auto at = [&](double q) {
    const auto i = static_cast<std::size_t>(std::ceil(q * static_cast<double>(values.size()))) - 1;
    return values[std::min(values.size() - 1, std::max<std::size_t>(i, 0))];
  };
  stats.median_ns = values.size() % 2 ? values[values.size() / 2]
                                      : 0.5 * (values[values.size() / 2 - 1] + values[values.size() / 2]);
  stats.p99_ns = at(0.99);
  stats.max_ns = values.back();
  return stats;
}

}  // namespace lightstage
