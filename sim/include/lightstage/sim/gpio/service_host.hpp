#pragma once
// The serving skeleton of lightstage-sim: listeners, each with the service
// that speaks to its connections, one thread per connection. The GPIO service
// (gpio_service.hpp) is one; the virtual camera (issue 4) is added beside it
// on its own listener, sharing the same VirtualChip.

#include "lightstage/common/link.hpp"

#include <memory>
#include <mutex>
#include <stop_token>
#include <string>
#include <thread>
#include <vector>

namespace lightstage::sim {

class ConnectionService {
 public:
  virtual ~ConnectionService() = default;
  // Serves one connection until the peer leaves, the service drops it, or
  // `stop` is requested (check it at least every ~100 ms). Must not throw.
  virtual void serve(std::unique_ptr<ByteLink> link, std::stop_token stop) = 0;
  virtual std::string name() const = 0;  // "gpio", for logs
};

class ServiceHost {
 public:
  ServiceHost() = default;
  ~ServiceHost();
  ServiceHost(const ServiceHost&) = delete;
  ServiceHost& operator=(const ServiceHost&) = delete;

  // Starts accepting connections on `listener` for `service` at once.
  void add(std::unique_ptr<LinkListener> listener, std::shared_ptr<ConnectionService> service);
  // Stops accepting, asks every connection to end and waits for them; the
  // listeners are destroyed (a Unix listener removes its socket file). Idempotent.
  void stop();

 private:
  struct Connection {
    std::jthread thread;
    std::shared_ptr<std::atomic<bool>> done;
  };
  struct Endpoint {
    std::unique_ptr<LinkListener> listener;
    std::shared_ptr<ConnectionService> service;
    std::jthread acceptor;
  };

  void accept_loop(Endpoint& endpoint, std::stop_token stop);
  void reap_finished();

  std::vector<std::unique_ptr<Endpoint>> endpoints_;
  std::mutex connections_mutex_;
  std::vector<Connection> connections_;
};

}  // namespace lightstage::sim
