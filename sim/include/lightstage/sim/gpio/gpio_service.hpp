#pragma once
// Serves the virtual chip over sim_gpio.proto (one MessageChannel per
// connection): chip info, line requests, sets, releases and run-time faults,
// each answered with the request's id; strobe edges are pushed, unsolicited
// (request_id 0), to the connection that requested the strobe line, when
// CLOCK_MONOTONIC reaches their time. A connection's lines are released when
// it goes away.

#include "lightstage/common/message_channel.hpp"
#include "lightstage/sim/gpio/fault.hpp"
#include "lightstage/sim/gpio/service_host.hpp"
#include "lightstage/sim/gpio/virtual_chip.hpp"

#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <thread>

namespace lightstage::proto::sim {
class ClientMessage;
class ServerMessage;
}  // namespace lightstage::proto::sim

namespace lightstage::sim::gpio {

class GpioService final : public ConnectionService {
 public:
  explicit GpioService(std::shared_ptr<VirtualChip> chip);
  ~GpioService() override;
  GpioService(const GpioService&) = delete;
  GpioService& operator=(const GpioService&) = delete;

  // drop-connection here; lose-strobe and stuck go to the chip. Throws InputError.
  void inject(const Fault& fault);

  void serve(std::unique_ptr<ByteLink> link, std::stop_token stop) override;
  std::string name() const override { return "gpio"; }

  VirtualChip& chip() { return *chip_; }

 private:
  struct DropFault {
    int after = 0;       // 0: not armed
    int generation = 0;  // bumped on every arming, so counts restart
  };

  void handle(ClientId client, const proto::sim::ClientMessage& message, proto::sim::ServerMessage& reply);
  void deliver(const std::vector<EdgeNotice>& notices);
  // Sends the strobe edges whose time has come, in time order whoever calls it.
  void deliver_due_strobes();
  void wake_strobe_clock();
  void run_strobe_clock(std::stop_token stop);

  std::shared_ptr<VirtualChip> chip_;
  std::mutex clients_mutex_;
  std::map<ClientId, std::shared_ptr<MessageChannel>> clients_;
  std::mutex drop_mutex_;
  DropFault drop_;
  std::mutex due_mutex_;
  std::mutex wake_mutex_;
  std::condition_variable_any wake_;
  bool woken_ = false;
  std::jthread strobe_clock_;  // last: starts after everything it uses
};

}  // namespace lightstage::sim::gpio
