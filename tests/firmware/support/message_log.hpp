#pragma once
// Collects the controller's unsolicited messages (its sink) for tests, and
// waits for one that matches.

#include "lightstage/proto/controller.pb.h"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <optional>
#include <vector>

namespace lightstage::firmware::testing {

class MessageLog {
 public:
  std::function<void(const proto::ControllerMessage&)> sink() {
    return [this](const proto::ControllerMessage& message) {
      const std::lock_guard lock(mutex_);
      messages_.push_back(message);
      changed_.notify_all();
    };
  }

  std::optional<proto::ControllerMessage> wait_for(
      const std::function<bool(const proto::ControllerMessage&)>& match,
      std::chrono::milliseconds timeout = std::chrono::seconds(10)) {
    std::unique_lock lock(mutex_);
    std::optional<proto::ControllerMessage> found;
    changed_.wait_for(lock, timeout, [&] {
      for (const auto& message : messages_) {
        if (match(message)) {
          found = message;
          return true;
        }
      }
      return false;
    });
    return found;
  }

  // Waits until `count` messages satisfy `match`; false on timeout.
  bool wait_count(const std::function<bool(const proto::ControllerMessage&)>& match, std::size_t count,
                  std::chrono::milliseconds timeout = std::chrono::seconds(10)) {
    std::unique_lock lock(mutex_);
    return changed_.wait_for(lock, timeout, [&] {
      return static_cast<std::size_t>(std::count_if(messages_.begin(), messages_.end(), match)) >= count;
    });
  }

  std::vector<proto::ControllerMessage> messages() const {
    const std::lock_guard lock(mutex_);
    return messages_;
  }

 private:
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<proto::ControllerMessage> messages_;
};

}  // namespace lightstage::firmware::testing
