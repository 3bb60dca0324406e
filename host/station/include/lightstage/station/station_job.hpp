#pragma once
// A long piece of the station's work — a capture, a calibration, a solve, a
// test sequence — on its own thread, followed from the page: how far it is,
// the time left, and how it ended. A stop asked for ends it at its next safe
// point (a capture between two controller sequences, the dome dark).

#include <atomic>
#include <chrono>
#include <cstddef>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

namespace lightstage::station {

class StationJob {
 public:
  enum class State { kRunning, kDone, kFailed, kStopped };
  // Returns the result shown with the finished job.
  using Work = std::function<nlohmann::json(StationJob& job)>;
  // Called on the job's thread once it ended, however.
  using OnEnd = std::function<void(const StationJob& job)>;

  StationJob(int id, std::string kind, nlohmann::json request, Work work, OnEnd on_end = {});
  ~StationJob();  // asks it to stop and waits
  StationJob(const StationJob&) = delete;
  StationJob& operator=(const StationJob&) = delete;

  // From the work: how far it is (`unit` names the items; "" = a share of `total`).
  void progress(std::size_t done, std::size_t total, const std::string& unit);
  void say(const std::string& message);
  bool stop_requested() const { return stop_; }

  void request_stop() { stop_ = true; }
  void wait();
  State state() const;
  bool running() const { return state() == State::kRunning; }
  const std::string& kind() const { return kind_; }
  const nlohmann::json& request() const { return request_; }
  // {id, kind, request, state, done, total, unit, seconds, eta_seconds, message, result | error}
  nlohmann::json to_json() const;

 private:
  void run(const Work& work);

  const int id_;
  const std::string kind_;
  const nlohmann::json request_;
  OnEnd on_end_;
  std::atomic<bool> stop_{false};
  mutable std::mutex mutex_;
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
