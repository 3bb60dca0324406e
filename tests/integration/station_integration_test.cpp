// `lightstage serve` as its own process on the simulated dome: killed in the
// middle of a capture, or with LEDs lit by hand, the dome goes dark within the
// controller's watchdog, and a new station resumes the capture from the page.
#include "dome_fixture.hpp"

#include "lightstage/common/child_process.hpp"
#include "lightstage/testing/paths.hpp"

#include <httplib.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <csignal>
#include <regex>
#include <thread>

namespace lightstage::testing {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using std::chrono::milliseconds;
using std::chrono::seconds;

const std::vector<std::string> kScene = {"--scene", "sphere",   "--lights", "distant", "--width",
                                         "64",      "--height", "64",       "--noise", "none"};

std::int64_t monotonic_ns() {
  // steady_clock is CLOCK_MONOTONIC on Linux: the clock the sim's timeline is stamped with.
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// A `lightstage serve` child on a free port, and a client of it.
class ServeProcess {
 public:
  ServeProcess(const SimulatedDome& dome, const fs::path& data, const std::string& name)
      : process_(bin_dir() / "lightstage",
                 {"serve", "--rig", dome.rig().string(), "--controller", dome.controller_uri(), "--camera",
                  dome.camera_uri(), "--listen", "127.0.0.1:0", "--data", data.string()},
                 scratch_dir() / (name + ".log")) {
    if (!process_.wait_for_output("the station is at", seconds(30)))
      throw Error("lightstage serve did not start: " + process_.output());
    std::smatch port;
    const std::string output = process_.output();
    if (!std::regex_search(output, port, std::regex(R"(127\.0\.0\.1:(\d+)/)")))
      throw Error("no address in: " + output);
    port_ = std::stoi(port[1]);
  }
  json post(const std::string& path, const json& body) {
    httplib::Client http("127.0.0.1", port_);
    const auto result = http.Post(path, {{"X-Lightstage-Client", "tab-a"}}, body.dump(), "application/json");
    if (!result) return {{"error", "no answer"}};
    return json::parse(result->body, nullptr, false);
  }
  json get(const std::string& path) {
    httplib::Client http("127.0.0.1", port_);
    const auto result = http.Get(path, {{"X-Lightstage-Client", "tab-a"}});
    if (!result) return {{"error", "no answer"}};
    return json::parse(result->body, nullptr, false);
  }
  ChildProcess& process() { return process_; }

 private:
  ChildProcess process_;
  int port_ = 0;
};

// Every LED interval ends no later than `by_ns`, and none is open.
void expect_dark_by(const SimulatedDome& dome, std::int64_t by_ns) {
  const Timeline timeline = dome.read_timeline();
  EXPECT_TRUE(timeline.leds_left_on().empty()) << "LEDs left lit";
  for (const auto& [line, intervals] : timeline.led_intervals()) {
    for (const Interval& interval : intervals)
      EXPECT_LE(interval.end_ns, by_ns)
          << line << " lit " << (interval.end_ns - by_ns) / 1e6 << " ms too long";
  }
}

TEST(StationIntegration, AServerKilledMidCaptureLeavesTheDomeDarkAndANewOneResumesIt) {
  SimulatedDome dome({{}, kScene, {}, true});
  const fs::path data = scratch_dir() / "data";
  std::int64_t watchdog_ns = 0;
  std::int64_t killed_ns = 0;
  {
    ServeProcess serve(dome, data, "serve-1");
    watchdog_ns =
        serve.get("/api/status")["dome"]["controller"]["watchdog_ms"].get<std::int64_t>() * 1'000'000;
    ASSERT_GT(watchdog_ns, 0);
    ASSERT_EQ(serve.post("/api/control", {{"name", "Ann"}})["you"], "operator");
    const json started =
        serve.post("/api/capture", {{"name", "sphere"}, {"exposure_us", 4000}, {"dark_frames", 2}});
    ASSERT_EQ(started["state"], "running") << started.dump();
    const auto deadline = std::chrono::steady_clock::now() + seconds(60);
    json job;
    do {
      job = serve.get("/api/job");
      std::this_thread::sleep_for(milliseconds(5));
    } while (job["state"] == "running" && job["done"].get<int>() < 20 &&
             std::chrono::steady_clock::now() < deadline);
    ASSERT_EQ(job["state"], "running") << "the capture ended before it could be interrupted: " << job.dump();
    serve.process().signal(SIGKILL);
    killed_ns = monotonic_ns();
    serve.process().wait(seconds(5));
  }
  std::this_thread::sleep_for(milliseconds(static_cast<int>(watchdog_ns / 1'000'000) + 500));
  expect_dark_by(dome, killed_ns + watchdog_ns + 300'000'000);

  ServeProcess again(dome, data, "serve-2");
  const json stack = again.get("/api/data")["stacks"][0];
  EXPECT_TRUE(stack["resumable"].get<bool>()) << stack.dump();
  EXPECT_GE(stack["frames"].get<int>(), 19);
  ASSERT_EQ(again.post("/api/control", {{"name", "Ann"}})["you"], "operator");
  const json resumed = again.post("/api/capture/resume", {{"name", "sphere"}});
  ASSERT_EQ(resumed["state"], "running") << resumed.dump();
  json job;
  const auto deadline = std::chrono::steady_clock::now() + seconds(60);
  do {
    std::this_thread::sleep_for(milliseconds(50));
    job = again.get("/api/job");
  } while (job["state"] == "running" && std::chrono::steady_clock::now() < deadline);
  ASSERT_EQ(job["state"], "done") << job.dump();
  EXPECT_EQ(job["result"]["frames"], 96);
  EXPECT_LT(job["result"]["taken_now"].get<int>(), 96 - 18);
}

TEST(StationIntegration, LedsLitByHandGoDarkWithinTheWatchdogWhenTheServerIsKilled) {
  SimulatedDome dome({{}, kScene, {}, true});
  ServeProcess serve(dome, scratch_dir() / "data", "serve");
  const std::int64_t watchdog_ns =
      serve.get("/api/status")["dome"]["controller"]["watchdog_ms"].get<std::int64_t>() * 1'000'000;
  ASSERT_EQ(serve.post("/api/control", {{"name", "Ann"}})["you"], "operator");
  const json lit = serve.post("/api/leds", {{"leds", {{{"id", 5}}}}});
  ASSERT_EQ(lit["controller"]["leds_on"], json::array({5})) << lit.dump();
  serve.process().signal(SIGKILL);
  const std::int64_t killed_ns = monotonic_ns();
  std::this_thread::sleep_for(milliseconds(static_cast<int>(watchdog_ns / 1'000'000) + 500));
  // Before its on-time limit (2 s on this rig): the watchdog darkened it.
  expect_dark_by(dome, killed_ns + watchdog_ns + 300'000'000);
}

}  // namespace
}  // namespace lightstage::testing
