#pragma once
// A request, raised from another thread, that the running job (a sequence or
// a static LED hold) stop now, and why. The job polls it between short sleeps.

#include "lightstage/proto/controller.pb.h"

#include <atomic>
#include <mutex>
#include <string>

namespace lightstage::firmware {

class StopFlag {
 public:
  // The first request wins; later ones keep its reason.
  void request(proto::Outcome why, const std::string& detail) {
    const std::lock_guard lock(mutex_);
    if (requested_) return;
    why_ = why;
    detail_ = detail;
    requested_ = true;
  }
  bool requested() const { return requested_; }
  proto::Outcome why() const {
    const std::lock_guard lock(mutex_);
    return why_;
  }
  std::string detail() const {
    const std::lock_guard lock(mutex_);
    return detail_;
  }
  void reset() {
    const std::lock_guard lock(mutex_);
    requested_ = false;
    why_ = proto::OK;
    detail_.clear();
  }

 private:
  mutable std::mutex mutex_;
  std::atomic<bool> requested_{false};
  proto::Outcome why_ = proto::OK;
  std::string detail_;
};

}  // namespace lightstage::firmware
