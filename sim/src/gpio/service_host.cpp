#include "lightstage/sim/gpio/service_host.hpp"

#include "lightstage/common/log.hpp"

#include <atomic>
#include <chrono>

namespace lightstage::sim {

ServiceHost::~ServiceHost() { stop(); }

void ServiceHost::add(std::unique_ptr<LinkListener> listener, std::shared_ptr<ConnectionService> service) {
  auto endpoint = std::make_unique<Endpoint>();
  endpoint->listener = std::move(listener);
  endpoint->service = std::move(service);
  Endpoint& ref = *endpoint;
  endpoints_.push_back(std::move(endpoint));
  ref.acceptor = std::jthread([this, &ref](std::stop_token stop) { accept_loop(ref, stop); });
}

void ServiceHost::accept_loop(Endpoint& endpoint, std::stop_token stop) {
  while (!stop.stop_requested()) {
    std::unique_ptr<ByteLink> link;
    try {
      link = endpoint.listener->accept(std::chrono::milliseconds(100));
    } catch (const std::exception& e) {
      logger("sim")->error("{}: accept failed: {}", endpoint.listener->describe(), e.what());
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      continue;
    }
    reap_finished();
    if (!link) continue;
    logger("sim")->info("{}: {} connection from {}", endpoint.listener->describe(), endpoint.service->name(),
                        link->describe());
    auto done = std::make_shared<std::atomic<bool>>(false);
    auto service = endpoint.service;
    const std::lock_guard lock(connections_mutex_);
    connections_.push_back(
        {std::jthread([service, done, owned = std::move(link)](std::stop_token token) mutable {
           service->serve(std::move(owned), token);
           done->store(true);
         }),
         done});
  }
}

void ServiceHost::reap_finished() {
  std::vector<Connection> finished;
  {
    const std::lock_guard lock(connections_mutex_);
    for (auto it = connections_.begin(); it != connections_.end();) {
      if (it->done->load()) {
        finished.push_back(std::move(*it));
        it = connections_.erase(it);
      } else {
        ++it;
      }
    }
  }
  // `finished` joins its threads here, outside the lock.
}

void ServiceHost::stop() {
  for (auto& endpoint : endpoints_) endpoint->acceptor.request_stop();
  for (auto& endpoint : endpoints_) {
    if (endpoint->acceptor.joinable()) endpoint->acceptor.join();
  }
  std::vector<Connection> connections;
  {
    const std::lock_guard lock(connections_mutex_);
    connections.swap(connections_);
  }
  for (auto& connection : connections) connection.thread.request_stop();
  connections.clear();  // joins
  endpoints_.clear();   // listeners remove their socket files
}

}  // namespace lightstage::sim
