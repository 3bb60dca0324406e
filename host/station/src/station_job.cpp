#include "lightstage/station/station_job.hpp"

#include "lightstage/common/log.hpp"

#include <chrono>
#include <exception>

namespace lightstage::station {

using Clock = std::chrono::steady_clock;

const char* state_name(StationJob::State state) {
  switch (state) {
    case StationJob::State::kRunning:
      return "running";
    case StationJob::State::kDone:
      return "done";
    case StationJob::State::kFailed:
      return "failed";
    case StationJob::State::kStopped:
      return "stopped";
  }
  return "unknown";
}

StationJob::StationJob(int id, std::string kind, nlohmann::json request, bool stoppable, Work work)
    : id_(id), kind_(std::move(kind)), request_(std::move(request)), stoppable_(stoppable) {
  thread_ = std::thread([this, work = std::move(work)] { run(work); });
}

StationJob::~StationJob() {
  request_stop();
  if (thread_.joinable()) thread_.join();
}

void StationJob::wait() const {
  std::unique_lock lock(mutex_);
  ended_changed_.wait(lock, [this] { return state_ != State::kRunning; });
}

void StationJob::run(const Work& work) {
  nlohmann::json result;
  State ended = State::kDone;
  std::string error;
  try {
    result = work(*this);
  } catch (const JobStopped& e) {
    ended = State::kStopped;
    error = e.what();
  } catch (const std::exception& e) {
    ended = State::kFailed;
    error = e.what();
  }
  if (ended == State::kFailed) logger("station")->warn("{} failed: {}", kind_, error);
  {
    const std::lock_guard lock(mutex_);
    state_ = ended;
    result_ = std::move(result);
    error_ = std::move(error);
    ended_ = Clock::now();
  }
  ended_changed_.notify_all();
}

void StationJob::progress(std::size_t done, std::size_t total, const std::string& unit) {
  const std::lock_guard lock(mutex_);
  if (!baseline_) baseline_ = done;  // a resumed capture starts with frames on disk
  done_ = done;
  total_ = total;
  unit_ = unit;
}

void StationJob::say(const std::string& message) {
  const std::lock_guard lock(mutex_);
  message_ = message;
}

StationJob::State StationJob::state() const {
  const std::lock_guard lock(mutex_);
  return state_;
}

nlohmann::json StationJob::to_json() const {
  const std::lock_guard lock(mutex_);
  const Clock::time_point end = state_ == State::kRunning ? Clock::now() : ended_;
  const double seconds = std::chrono::duration<double>(end - started_).count();
  nlohmann::json j = {
      {"id", id_},           {"kind", kind_},          {"request", request_}, {"state", state_name(state_)},
      {"done", done_},       {"total", total_},        {"unit", unit_},       {"seconds", seconds},
      {"message", message_}, {"stoppable", stoppable_}};
  // Time left at the pace so far (unknown until some work is done).
  if (state_ == State::kRunning && baseline_ && done_ > *baseline_ && total_ >= done_)
    j["eta_seconds"] =
        seconds / static_cast<double>(done_ - *baseline_) * static_cast<double>(total_ - done_);
  else
    j["eta_seconds"] = nullptr;
  if (state_ == State::kDone) j["result"] = result_;
  if (state_ == State::kFailed || state_ == State::kStopped) j["error"] = error_;
  return j;
}

}  // namespace lightstage::station
