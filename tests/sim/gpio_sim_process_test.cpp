// lightstage-sim as a process: startup line, serving the `sim:` backend,
// the --timeline file (also after SIGKILL), SIGTERM with socket removal, and
// bad command lines.
#include "gpio_test_support.hpp"
#include "lightstage/common/child_process.hpp"
#include "lightstage/common/clock.hpp"
#include "lightstage/sim/gpio/sim_chip.hpp"
#include "lightstage/testing/paths.hpp"
#include "lightstage/testing/run.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <csignal>
#include <fstream>

namespace lightstage::sim::gpio {
namespace {

using lightstage::ChildProcess;
using lightstage::testing::bin_dir;

constexpr auto kStartTimeout = std::chrono::seconds(20);

std::vector<nlohmann::json> read_json_lines(const std::filesystem::path& path) {
  std::vector<nlohmann::json> lines;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) lines.push_back(nlohmann::json::parse(line));
  return lines;
}

class SimProcessTest : public ::testing::Test {
 protected:
  void start(std::vector<std::string> extra = {}) {
    dir = lightstage::testing::scratch_dir();
    socket = lightstage::testing::socket_dir() /
             (std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + ".sock");
    timeline = dir / "timeline.jsonl";
    std::vector<std::string> args = {
        "--rig",      (lightstage::testing::source_dir() / "hw/rigs/sim-dome.yaml").string(),
        "--listen",   "unix:" + socket.string(),
        "--timeline", timeline.string()};
    args.insert(args.end(), extra.begin(), extra.end());
    sim = std::make_unique<ChildProcess>(bin_dir() / "lightstage-sim", args, dir / "sim.log");
    ASSERT_TRUE(sim->wait_for_output("lightstage-sim: listening on unix:" + socket.string(), kStartTimeout))
        << sim->output();
  }

  std::filesystem::path dir, socket, timeline;
  std::unique_ptr<ChildProcess> sim;
};

TEST_F(SimProcessTest, ServesTheBackendAndStopsCleanlyOnSigterm) {
  start();
  {
    const auto chip = connect_sim_chip("unix:" + socket.string());
    const std::vector<unsigned> led = {17};
    auto lines = chip->request_outputs(led, {}, {}, "test");
    lines->set(std::vector<int>{1}, 1'000);
    lines->set(std::vector<int>{0}, 2'000);
    EXPECT_EQ(chip->info().consumers[17], "test");
  }
  sim->signal(SIGTERM);
  EXPECT_EQ(sim->wait(std::chrono::seconds(20)), std::optional<int>(0)) << sim->output();
  EXPECT_FALSE(std::filesystem::exists(socket));
  const auto lines = read_json_lines(timeline);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0]["t_ns"], 1'000);
  EXPECT_EQ(lines[0]["line"], "LED17");
  EXPECT_EQ(lines[0]["value"], 1);
  EXPECT_EQ(lines[1]["t_ns"], 2'000);
  EXPECT_EQ(lines[1]["value"], 0);
}

TEST_F(SimProcessTest, TheTimelineSurvivesSigkill) {
  start({"--strobe-delay-us", "0", "--strobe-exposure-us", "500"});
  const auto chip = connect_sim_chip("unix:" + socket.string());
  const std::vector<unsigned> trigger_line = {100};
  auto trigger = chip->request_outputs(trigger_line, {}, {}, "test");
  auto strobe = chip->request_edges(101, false, "test");
  const std::int64_t t0 = monotonic_now_ns();
  trigger->set(std::vector<int>{1}, t0);
  ASSERT_TRUE(strobe->wait_until(t0 + 10'000'000'000).has_value());
  const auto end = strobe->wait_until(t0 + 10'000'000'000);
  ASSERT_TRUE(end.has_value());
  EXPECT_EQ(end->t_ns, t0 + 500'000);
  sim->signal(SIGKILL);
  EXPECT_EQ(sim->wait(std::chrono::seconds(20)), std::optional<int>(128 + SIGKILL));
  const auto lines = read_json_lines(timeline);
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_EQ(lines[0]["line"], "TRIGGER");
  EXPECT_EQ(lines[0]["t_ns"], t0);
  EXPECT_EQ(lines[1]["line"], "STROBE");
  EXPECT_EQ(lines[1]["value"], 1);
  EXPECT_EQ(lines[2]["line"], "STROBE");
  EXPECT_EQ(lines[2]["t_ns"], t0 + 500'000);
}

TEST_F(SimProcessTest, FaultsFromTheCommandLine) {
  start({"--fault", "lose-strobe:1", "--fault", "stuck:LED3", "--strobe-exposure-us", "100"});
  const auto chip = connect_sim_chip("unix:" + socket.string());
  const std::vector<unsigned> lines = {3, 100};
  auto outputs = chip->request_outputs(lines, {}, {}, "test");
  auto strobe = chip->request_edges(101, false, "test");
  const std::int64_t t0 = monotonic_now_ns();
  outputs->set(std::vector<int>{1, 1}, t0);
  EXPECT_FALSE(strobe->wait_until(t0 + 100'000'000).has_value()) << "the first trigger's strobe is lost";
  sim->signal(SIGTERM);
  EXPECT_EQ(sim->wait(std::chrono::seconds(20)), std::optional<int>(0));
  const auto entries = read_json_lines(timeline);
  // LED3 is stuck dark: only the trigger changed — asserted, then released
  // (inactive) when the connection went.
  ASSERT_EQ(entries.size(), 2u);
  EXPECT_EQ(entries[0]["line"], "TRIGGER");
  EXPECT_EQ(entries[0]["value"], 1);
  EXPECT_EQ(entries[1]["line"], "TRIGGER");
  EXPECT_EQ(entries[1]["value"], 0);
  EXPECT_NE(sim->output().find("lose-strobe:1"), std::string::npos);
}

TEST(SimProcessCommandLine, BadFlagsAreRefusedWithAMessage) {
  const auto sim = bin_dir() / "lightstage-sim";
  const auto no_listen = lightstage::testing::run(sim, {});
  EXPECT_EQ(no_listen.exit_code, 2);
  EXPECT_NE(no_listen.err.find("--listen"), std::string::npos) << no_listen.err;
  const auto socket = (lightstage::testing::socket_dir() / "bad.sock").string();
  const auto bad_fault = lightstage::testing::run(sim, {"--listen", "unix:" + socket, "--fault", "melt:1"});
  EXPECT_EQ(bad_fault.exit_code, 1);
  EXPECT_NE(bad_fault.err.find("melt"), std::string::npos) << bad_fault.err;
  const auto bad_rig =
      lightstage::testing::run(sim, {"--listen", "unix:" + socket, "--rig", "/nonexistent.yaml"});
  EXPECT_EQ(bad_rig.exit_code, 1);
  EXPECT_NE(bad_rig.err.find("/nonexistent.yaml"), std::string::npos) << bad_rig.err;
  const auto bad_exposure =
      lightstage::testing::run(sim, {"--listen", "unix:" + socket, "--strobe-exposure-us", "0"});
  EXPECT_EQ(bad_exposure.exit_code, 1);
  EXPECT_NE(bad_exposure.err.find("exposure"), std::string::npos) << bad_exposure.err;
}

}  // namespace
}  // namespace lightstage::sim::gpio
