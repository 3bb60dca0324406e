#include "lightstage/firmware/controller_server.hpp"

#include "lightstage/common/log.hpp"
#include "lightstage/common/rig_fingerprint.hpp"
#include "lightstage/common/version.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <ctime>

namespace lightstage::firmware {
namespace {

proto::ControllerMessage ack(std::uint32_t request_id) {
  proto::ControllerMessage reply;
  reply.set_request_id(request_id);
  reply.mutable_ack();
  return reply;
}

proto::ControllerMessage reply_to(std::uint32_t request_id, const std::optional<Refusal>& refusal) {
  if (!refusal) return ack(request_id);
  return error_reply(request_id, refusal->code, refusal->message);
}

std::string utc_time(std::chrono::system_clock::time_point t) {
  const std::time_t seconds = std::chrono::system_clock::to_time_t(t);
  std::tm parts{};
  gmtime_r(&seconds, &parts);
  std::array<char, 32> text{};
  const std::size_t n = std::strftime(text.data(), text.size(), "%Y-%m-%dT%H:%M:%SZ", &parts);
  return std::string(text.data(), n);
}

std::int64_t ms_between(std::chrono::steady_clock::time_point from,
                        std::chrono::steady_clock::time_point to) {
  return std::chrono::duration_cast<std::chrono::milliseconds>(to - from).count();
}

}  // namespace

proto::ControllerMessage error_reply(std::uint32_t request_id, proto::Error::Code code,
                                     const std::string& message) {
  proto::ControllerMessage reply;
  reply.set_request_id(request_id);
  reply.mutable_error()->set_code(code);
  reply.mutable_error()->set_message(message);
  return reply;
}

ControllerServer::ControllerServer(Controller& controller, ServerOptions options)
    : controller_(controller), options_(std::move(options)) {}

void ControllerServer::serve(LinkListener& listener, const std::atomic<bool>& stop) {
  while (!stop && !controller_.gpio_failure()) {
    std::unique_ptr<ByteLink> link = listener.accept(std::chrono::milliseconds(50));
    if (link) serve_client(std::move(link), stop, &listener);
  }
  controller_.stop(proto::SHUTDOWN, "lightstage-domed shutting down");
}

void ControllerServer::refuse_extra_client(LinkListener& listener, Session& holder) {
  std::unique_ptr<ByteLink> extra = listener.accept(std::chrono::milliseconds(0));
  if (!extra) return;
  holder.contested = true;
  const auto held_ms = ms_between(holder.connected, std::chrono::steady_clock::now());
  const std::string why = fmt::format(
      "another host controls this dome: {}, connected since {} ({} ms ago){}; try again later", holder.peer,
      utc_time(holder.connected_wall), held_ms, holder.negotiated ? "" : ", no Hello yet");
  logger("firmware")->warn("{}: refused: {}", extra->describe(), why);
  try {
    MessageChannel channel(std::move(extra));
    channel.send(error_reply(0, proto::Error::BUSY, why));
    // Closing with the host's hello still unread would reset its connection
    // and lose the BUSY reply on its side: take what it sends until it hangs
    // up (it does on BUSY), for a moment at most.
    std::array<std::uint8_t, 256> unread{};
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(200);
    while (std::chrono::steady_clock::now() < deadline)
      channel.link().read(unread, std::chrono::milliseconds(20));
  } catch (const std::exception& e) {
    logger("firmware")->debug("refusing a second client: {}", e.what());
  }
}

std::optional<std::string> ControllerServer::expired(const Session& session, const MessageChannel& channel,
                                                     std::chrono::steady_clock::time_point now) const {
  if (!session.negotiated) {
    if (now - session.connected <= options_.hello_timeout) return std::nullopt;
    if (channel.bytes_received() == 0 && !session.contested)
      return std::nullopt;  // nobody there, nobody waiting
    return fmt::format("no Hello within {} ms of connecting; hanging up", options_.hello_timeout.count());
  }
  const auto lease = std::max(options_.idle_lease, std::chrono::milliseconds(session.watchdog_ms));
  if (now - session.last_message <= lease) return std::nullopt;
  return fmt::format("no valid message for {} ms (lease {} ms); hanging up",
                     ms_between(session.last_message, now), lease.count());
}

void ControllerServer::serve_client(std::unique_ptr<ByteLink> link, const std::atomic<bool>& stop,
                                    LinkListener* listener) {
  Session session;
  session.peer = link->describe();
  session.connected = std::chrono::steady_clock::now();
  session.connected_wall = std::chrono::system_clock::now();
  session.last_message = session.connected;
  const std::string& peer = session.peer;
  logger("firmware")->info("{}: host connected", peer);
  MessageChannel channel(std::move(link));
  controller_.set_sink([&channel](const proto::ControllerMessage& message) { channel.send(message); });
  // Sequences belong to the session that uploaded them.
  struct ForgetSequences {
    Controller& controller;
    ~ForgetSequences() { controller.forget_sequences(); }
  } forget{controller_};
  try {
    while (!stop && !controller_.gpio_failure()) {
      proto::HostMessage request;
      bool received = false;
      try {
        received = channel.receive(request, kPoll);
      } catch (const ProtocolError& e) {
        // Answered, but no proof of a live host: bytes that do not parse
        // must not keep the watchdog or the lease fed.
        logger("firmware")->warn("{}", e.what());
        channel.send(error_reply(0, proto::Error::MALFORMED_FRAME, e.what()));
        received = false;
      }
      if (received) {
        if (request.body_case() != proto::HostMessage::BODY_NOT_SET) {
          session.last_message = std::chrono::steady_clock::now();
        }
        if (auto reply = handle(request, session, channel)) channel.send(*reply);
      }
      // Checked after every message too, so that a flood of messages that
      // prove nothing cannot keep the checks from running.
      const auto now = std::chrono::steady_clock::now();
      if (const auto why = expired(session, channel, now)) {
        logger("firmware")->warn("{}: {}", peer, *why);
        controller_.stop(proto::WATCHDOG, fmt::format("session of {} expired: {}", peer, *why));
        channel.send(error_reply(0, proto::Error::SESSION_EXPIRED, *why));
        controller_.set_sink({});
        return;
      }
      if (session.watchdog_ms > 0 && controller_.active() &&
          now - session.last_message > std::chrono::milliseconds(session.watchdog_ms)) {
        controller_.stop(proto::WATCHDOG,
                         fmt::format("watchdog: no valid message from the host for {} ms (timeout {} ms)",
                                     ms_between(session.last_message, now), session.watchdog_ms));
      }
      if (listener) refuse_extra_client(*listener, session);
    }
  } catch (const LinkClosed& e) {
    logger("firmware")->info("{}: host disconnected ({})", peer, e.what());
    controller_.set_sink({});
    controller_.stop(proto::LINK_LOST, fmt::format("link to the host lost: {}", e.what()));
    return;
  }
  if (const auto failure = controller_.gpio_failure()) {
    logger("firmware")->critical("{}: GPIO backend lost ({}); no longer serving", peer, *failure);
    controller_.stop(proto::GPIO_ERROR, fmt::format("GPIO backend lost: {}", *failure));
    controller_.set_sink({});
    return;
  }
  // Stopped (SIGINT/SIGTERM): darken while the host can still hear why.
  controller_.stop(proto::SHUTDOWN, "lightstage-domed shutting down");
  controller_.set_sink({});
}

proto::ControllerMessage ControllerServer::info(const Session& session) const {
  const Rig& rig = controller_.rig();
  proto::ControllerMessage reply;
  proto::Info& info = *reply.mutable_info();
  info.set_protocol_version(session.version);
  info.set_firmware_version(kVersion);
  info.set_rig_name(rig.name);
  info.set_rig_fingerprint(rig_fingerprint(rig));
  info.set_led_count(static_cast<std::uint32_t>(rig.leds.size()));
  for (const Led& led : rig.leds) {
    proto::Led& entry = *info.add_leds();
    entry.set_id(static_cast<std::uint32_t>(led.id));
    entry.set_max_on_us(static_cast<float>(led.limits.max_on_us));
    entry.set_max_duty(static_cast<float>(led.limits.max_duty));
    entry.set_duty_window_us(static_cast<float>(led.limits.duty_window_us));
  }
  proto::Capabilities& caps = *info.mutable_capabilities();
  caps.set_strobe_input(controller_.has_strobe());
  caps.set_dimming(false);
  caps.set_realtime(controller_.realtime());
  caps.set_max_sequence_steps(Sequencer::kMaxSteps);
  caps.set_watchdog_timeout_ms(session.watchdog_ms);
  caps.set_max_watchdog_timeout_ms(options_.max_watchdog_ms);
  info.set_gpio_uri(options_.gpio_uri);
  info.set_clock_ns(controller_.status().clock_ns());
  return reply;
}

std::optional<proto::ControllerMessage> ControllerServer::handle(const proto::HostMessage& request,
                                                                 Session& session, MessageChannel& channel) {
  const std::uint32_t id = request.request_id();
  if (request.has_hello()) {
    const proto::Hello& hello = request.hello();
    const std::uint32_t host_max = hello.protocol_version();
    const std::uint32_t host_min = hello.min_protocol_version() ? hello.min_protocol_version() : host_max;
    if (host_max < kMinProtocolVersion || host_min > kProtocolVersion || host_min > host_max) {
      return error_reply(id, proto::Error::VERSION_MISMATCH,
                         fmt::format("host speaks protocol versions {}..{}, this controller {}..{}", host_min,
                                     host_max, kMinProtocolVersion, kProtocolVersion));
    }
    session.negotiated = true;
    session.version = std::min(host_max, kProtocolVersion);
    const std::uint32_t asked =
        hello.watchdog_timeout_ms() ? hello.watchdog_timeout_ms() : options_.default_watchdog_ms;
    session.watchdog_ms = std::clamp(asked, options_.min_watchdog_ms, options_.max_watchdog_ms);
    logger("firmware")
        ->info("{}: hello from \"{}\", protocol {}, watchdog {} ms", channel.link().describe(),
               hello.client(), session.version, session.watchdog_ms);
    proto::ControllerMessage reply = info(session);
    reply.set_request_id(id);
    return reply;
  }
  if (!session.negotiated) {
    return error_reply(id, proto::Error::NOT_NEGOTIATED, "send Hello first (protocol version negotiation)");
  }
  switch (request.body_case()) {
    case proto::HostMessage::kSetLeds:
      controller_.clear_fault();
      return reply_to(id, controller_.set_leds(request.set_leds()));
    case proto::HostMessage::kUpload:
      controller_.clear_fault();
      return reply_to(id, controller_.upload(request.upload().sequence()));
    case proto::HostMessage::kRun: {
      controller_.clear_fault();
      const auto refusal = controller_.run(request.run().sequence_id(), request.run().start_ns(),
                                           [&] { channel.send(ack(id)); });
      if (!refusal) return std::nullopt;  // acknowledged before the first step
      return reply_to(id, refusal);
    }
    case proto::HostMessage::kAbort:
      controller_.stop(proto::ABORTED_BY_HOST, "aborted by the host");
      controller_.clear_fault();
      return ack(id);
    case proto::HostMessage::kStatus: {
      proto::ControllerMessage reply;
      reply.set_request_id(id);
      *reply.mutable_status() = controller_.status();
      return reply;
    }
    case proto::HostMessage::kHeartbeat:
      if (id == 0) return std::nullopt;
      return ack(id);
    case proto::HostMessage::kHello:
    case proto::HostMessage::BODY_NOT_SET:
      break;
  }
  return error_reply(id, proto::Error::BAD_REQUEST,
                     "empty or unknown request (a newer host? this controller speaks protocol " +
                         std::to_string(session.version) + ")");
}

}  // namespace lightstage::firmware
