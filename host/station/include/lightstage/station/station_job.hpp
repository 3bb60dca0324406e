#pragma once
// A long piece of the station's work — a capture, a calibration, a solve, a
// test sequence — on its own thread, followed from the page: how far it is,
// the time left, and how it ended. A stop asked for ends it at its next safe
// point (a capture between two controller sequences, the dome dark), when
// the work has one: calibrations and exports run to their end.

#include "lightstage/common/error.hpp"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

namespace lightstage::station {

// Thrown by a job's work at a safe point after a stop was asked for: the job
// ends "stopped". Any other error ends it "failed", stop asked for or not.
class JobStopped : public Error {
 public:
  using Error::Error;
};

class StationJob {
 public:
  enum class State { kRunning, kDone, kFailed, kStopped };
  // Returns the result shown with the finished job.
  using Work = std::function<nlohmann::json(StationJob& job)>;

  StationJob(int id, std::string kind, nlohmann::json request, bool stoppable, Work work);
  ~StationJob();  // asks it to stop and waits for its thread
  StationJob(const StationJob&) = delete;
  StationJob& operator=(const StationJob&) = delete;

  // From the work: how far it is (`unit` names the items; "" = a share of `total`).
  void progress(std::size_t done, std::size_t total, const std::string& unit);
  void say(const std::string& message);
  bool stop_requested() const { return stop_; }

  void request_stop() { stop_ = true; }
  bool stoppable() const { return stoppable_; }
  // Until the work ended (from any number of threads).
  void wait() const;
  State state() const;
  bool running() const { return state() == State::kRunning; }
  const std::string& kind() const { return kind_; }
  const nlohmann::json& request() const { return request_; }
  // {id, kind, request, state, done, total, unit, seconds, eta_seconds, message, stoppable, result | error}
  nlohmann::json to_json() const;

 private:
  void run(const Work& work);

  const int id_;
  const std::string kind_;
  const nlohmann::json request_;
  const bool stoppable_;
  std::atomic<bool> stop_{false};
  mutable std::mutex mutex_;
  mutable std::condition_variable ended_changed_;
  State state_ = State::kRunning;
  std::size_t done_ = 0, total_ = 0;
  std::optional<std::size_t> baseline_;  // `done` when progress was first told
  std::string unit_, message_, error_;
  nlohmann::json result_;
  std::chrono::steady_clock::time_point started_ = std::chrono::steady_clock::now(), ended_{};
  std::thread thread_;
};

const char* state_name(StationJob::State state);

}  // namespace lightstage::station
