#include "lightstage/host/controller/led_hold.hpp"

#include <algorithm>
#include <thread>

namespace lightstage {
namespace {

// How often the hold asks the controller for its status.
constexpr std::chrono::milliseconds kStatusPoll{50};

}  // namespace

LedHold hold_leds(ControllerClient& client, const std::vector<std::pair<std::uint32_t, float>>& levels,
                  std::chrono::milliseconds duration) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  const auto until = start + duration;
  client.set_leds(levels);
  proto::Status status = client.status();
  while (status.state() != proto::Status::FAULT && Clock::now() < until) {
    std::this_thread::sleep_for(std::min<Clock::duration>(kStatusPoll, until - Clock::now()));
    status = client.status();
  }
  LedHold hold;
  hold.held_ms = std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - start).count();
  client.all_off();
  hold.faulted = status.state() == proto::Status::FAULT;
  if (hold.faulted) hold.fault = status.last_fault();
  return hold;
}

}  // namespace lightstage
