#include "lightstage/station/station_job.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <thread>

namespace lightstage::station {
namespace {

using nlohmann::json;

// Work that runs until stopped, then ends as `how` says.
StationJob::Work until_stopped(std::function<json()> how) {
  return [how](StationJob& job) {
    job.progress(1, 10, "steps");
    while (!job.stop_requested()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    return how();
  };
}

TEST(StationJob, AStopHonouredIsStoppedAnErrorAfterAStopIsAFailure) {
  StationJob honoured(1, "capture", json::object(), true,
                      until_stopped([]() -> json { throw JobStopped("stopped at a safe point"); }));
  honoured.request_stop();
  honoured.wait();
  EXPECT_EQ(honoured.to_json()["state"], "stopped");
  EXPECT_EQ(honoured.to_json()["error"], "stopped at a safe point");

  StationJob failed(2, "solve", json::object(), true,
                    until_stopped([]() -> json { throw std::runtime_error("disk full"); }));
  failed.request_stop();
  failed.wait();
  EXPECT_EQ(failed.to_json()["state"], "failed") << "a failure after a stop is still a failure";
  EXPECT_EQ(failed.to_json()["error"], "disk full");

  StationJob done(3, "solve", json::object(), true, until_stopped([] { return json{{"pixels", 5}}; }));
  done.request_stop();
  done.wait();
  EXPECT_EQ(done.to_json()["state"], "done");
  EXPECT_EQ(done.to_json()["result"]["pixels"], 5);
}

TEST(StationJob, ManyMayWaitForItsEndAndItSaysWhetherItCanBeStopped) {
  std::atomic<bool> release{false};
  StationJob job(4, "calibration", json{{"name", "c"}}, false, [&](StationJob&) {
    while (!release) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    return json::object();
  });
  EXPECT_FALSE(job.to_json()["stoppable"].get<bool>());
  EXPECT_TRUE(job.running());
  std::atomic<int> woken{0};
  std::vector<std::thread> waiters;
  for (int i = 0; i < 3; ++i)
    waiters.emplace_back([&] {
      job.wait();
      ++woken;
    });
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_EQ(woken, 0);
  release = true;
  for (auto& waiter : waiters) waiter.join();
  EXPECT_EQ(woken, 3);
  EXPECT_EQ(job.to_json()["state"], "done");
  EXPECT_EQ(job.to_json()["request"]["name"], "c");
}

}  // namespace
}  // namespace lightstage::station
