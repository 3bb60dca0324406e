#include "lightstage/sim/gpio/gpio_service.hpp"

#include "lightstage/common/clock.hpp"
#include "lightstage/common/log.hpp"
#include "lightstage/proto/sim_gpio.pb.h"

#include <sys/prctl.h>

#include <chrono>
#include <vector>

namespace lightstage::sim::gpio {
namespace {

namespace pb = lightstage::proto::sim;

std::chrono::steady_clock::time_point steady_at(std::int64_t t_ns) {
  // steady_clock is CLOCK_MONOTONIC on Linux: the clock the firmware stamps with.
  return std::chrono::steady_clock::time_point(std::chrono::nanoseconds(t_ns));
}

void set_error(pb::ServerMessage& reply, const std::string& message) {
  reply.mutable_error()->set_message(message);
}

}  // namespace

GpioService::GpioService(std::shared_ptr<VirtualChip> chip)
    : chip_(std::move(chip)), strobe_clock_([this](std::stop_token stop) { run_strobe_clock(stop); }) {}

GpioService::~GpioService() {
  strobe_clock_.request_stop();
  wake_.notify_all();
}

void GpioService::inject(const Fault& fault) {
  if (fault.kind != Fault::Kind::kDropConnection) {
    chip_->inject(fault);
    return;
  }
  const std::lock_guard lock(drop_mutex_);
  drop_.after = fault.count;
  ++drop_.generation;
  logger("sim")->info("fault armed: {}", fault.text);
}

void GpioService::serve(std::unique_ptr<ByteLink> link, std::stop_token stop) {
  const std::string peer = link->describe();
  auto channel = std::make_shared<MessageChannel>(std::move(link));
  const ClientId client = chip_->connect();
  {
    const std::lock_guard lock(clients_mutex_);
    clients_[client] = channel;
  }
  int generation = 0;
  {
    const std::lock_guard lock(drop_mutex_);
    generation = drop_.generation;
  }
  int since_armed = 0;
  // Frees the connection's lines; done before the sim itself hangs up, so a
  // client that sees the close and reconnects finds its lines free.
  const auto leave = [&] {
    {
      const std::lock_guard lock(clients_mutex_);
      clients_.erase(client);
    }
    chip_->disconnect(client);
  };
  try {
    while (!stop.stop_requested()) {
      pb::ClientMessage message;
      pb::ServerMessage reply;
      try {
        if (!channel->receive(message, std::chrono::milliseconds(100))) continue;
      } catch (const ProtocolError& e) {
        // A damaged frame: say so and keep serving (the channel has resynchronised).
        set_error(reply, e.what());
        channel->send(reply);
        continue;
      }
      {
        // Counts restart when a drop-connection fault is armed.
        const std::lock_guard lock(drop_mutex_);
        if (generation != drop_.generation) {
          generation = drop_.generation;
          since_armed = 0;
        }
      }
      reply.set_request_id(message.request_id());
      handle(client, message, reply);
      channel->send(reply);

      bool drop = false;
      {
        const std::lock_guard lock(drop_mutex_);
        if (generation != drop_.generation) {
          generation = drop_.generation;  // armed by this very message: count from the next
          since_armed = 0;
        } else if (drop_.after > 0 && ++since_armed >= drop_.after) {
          drop_.after = 0;
          drop = true;
        }
      }
      if (drop) {
        logger("sim")->warn("fault drop-connection:{}: closing {}", since_armed, peer);
        leave();
        channel->link().shutdown();
        break;
      }
    }
  } catch (const LinkClosed&) {
    logger("sim")->info("gpio client {} ({}) left; its lines are released", client, peer);
  } catch (const std::exception& e) {
    logger("sim")->error("{}: {}", peer, e.what());
  }
  leave();
}

void GpioService::handle(ClientId client, const pb::ClientMessage& message, pb::ServerMessage& reply) {
  // Edges due by now go out before this answer, as a kernel would have queued them already even
  // when the strobe clock's thread runs late: a client's round trip sees every edge up to it.
  deliver_due_strobes();
  try {
    switch (message.body_case()) {
      case pb::ClientMessage::kChipInfo: {
        const auto info = chip_->info();
        auto* out = reply.mutable_chip_info();
        out->set_label(info.label);
        for (const auto& name : info.line_names) out->add_line_names(name);
        for (const auto& consumer : info.consumers) out->add_line_consumers(consumer);
        return;
      }
      case pb::ClientMessage::kRequestLines: {
        const auto& request = message.request_lines();
        const std::vector<unsigned> offsets(request.offsets().begin(), request.offsets().end());
        const std::vector<bool> active_low_bits(request.active_low().begin(), request.active_low().end());
        // std::span needs contiguous bools: vector<bool> is not.
        const auto active_low = std::make_unique<bool[]>(active_low_bits.size() + 1);
        for (std::size_t i = 0; i < active_low_bits.size(); ++i) active_low[i] = active_low_bits[i];
        const std::vector<int> initial(request.initial_values().begin(), request.initial_values().end());
        chip_->request_lines(client, offsets, request.output(), request.consumer(),
                             std::span<const bool>(active_low.get(), active_low_bits.size()), initial,
                             request.t_ns());
        reply.mutable_ack();
        return;
      }
      case pb::ClientMessage::kSetValues: {
        const auto& set = message.set_values();
        const std::vector<unsigned> offsets(set.offsets().begin(), set.offsets().end());
        const std::vector<int> values(set.values().begin(), set.values().end());
        deliver(chip_->set_values(client, offsets, values, set.t_ns()));
        wake_strobe_clock();  // a trigger may have scheduled a strobe
        reply.mutable_ack();
        return;
      }
      case pb::ClientMessage::kReleaseLines: {
        const auto& release = message.release_lines();
        const std::vector<unsigned> offsets(release.offsets().begin(), release.offsets().end());
        chip_->release_lines(client, offsets);
        reply.mutable_ack();
        return;
      }
      case pb::ClientMessage::kInjectFault:
        inject(parse_fault(message.inject_fault().spec()));
        reply.mutable_ack();
        return;
      case pb::ClientMessage::BODY_NOT_SET:
        break;
    }
    set_error(reply, "lightstage-sim: a message without a known body (request_id " +
                         std::to_string(message.request_id()) + ")");
  } catch (const Error& e) {
    set_error(reply, e.what());
  }
}

void GpioService::deliver(const std::vector<EdgeNotice>& notices) {
  for (const auto& notice : notices) {
    std::shared_ptr<MessageChannel> channel;
    {
      const std::lock_guard lock(clients_mutex_);
      const auto it = clients_.find(notice.client);
      if (it == clients_.end()) continue;
      channel = it->second;
    }
    pb::ServerMessage message;
    message.set_request_id(0);
    auto* edge = message.mutable_edge();
    edge->set_offset(notice.edge.offset);
    edge->set_rising(notice.edge.rising);
    edge->set_t_ns(notice.edge.t_ns);
    try {
      channel->send(message);
    } catch (const LinkClosed&) {
      // The connection is going away; its serve() loop cleans up.
    }
  }
}

void GpioService::deliver_due_strobes() {
  const std::lock_guard lock(due_mutex_);
  deliver(chip_->run_due(monotonic_now_ns()));
}

void GpioService::wake_strobe_clock() {
  {
    const std::lock_guard lock(wake_mutex_);
    woken_ = true;
  }
  wake_.notify_one();
}

void GpioService::run_strobe_clock(std::stop_token stop) {
  // Timed waits of ordinary threads may run late by the timer slack (50 us by
  // default); strobe edges should leave as close to their time as the machine allows.
  prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
  while (!stop.stop_requested()) {
    {
      std::unique_lock lock(wake_mutex_);
      const auto due = chip_->next_due_ns();
      if (due) {
        wake_.wait_until(lock, stop, steady_at(*due), [this] { return woken_; });
      } else {
        wake_.wait(lock, stop, [this] { return woken_; });
      }
      woken_ = false;
    }
    if (stop.stop_requested()) break;
    deliver_due_strobes();
  }
}

}  // namespace lightstage::sim::gpio
