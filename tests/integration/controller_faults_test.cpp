// The controller fails loudly, as separate processes over the simulated dome:
// `lightstage ctl leds` reports the firmware's cut-off, lightstage-domed exits
// with its documented codes when the GPIO backend is gone (while serving, or
// already at --check).
#include "dome_fixture.hpp"

#include "lightstage/common/child_process.hpp"
#include "lightstage/testing/paths.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <csignal>
#include <limits>
#include <string>

namespace lightstage::testing {
namespace {

using namespace std::chrono_literals;

// A ctl command against `dome`; its exit code, its output in `output`.
int run_ctl(const SimulatedDome& dome, std::vector<std::string> args, const std::string& name,
            std::string& output) {
  std::vector<std::string> all = {"ctl", "--controller", dome.controller_uri()};
  all.insert(all.end(), args.begin(), args.end());
  ChildProcess ctl(bin_dir() / "lightstage", all, scratch_dir() / (name + ".log"));
  const auto code = ctl.wait(30s);
  output = ctl.output();
  EXPECT_TRUE(code.has_value()) << "ctl did not finish: " << output;
  return code.value_or(-1);
}

TEST(ControllerFaults, CtlLedsReportsTheFirmwareCutOffAndExitsNonZero) {
  const auto rig = rig_with_limits(source_dir() / "hw/rigs/sim-dome.yaml", 50'000, 0.2, 1'000'000,
                                   scratch_dir() / "tight.yaml");
  SimulatedDome dome({rig, {}, {}});
  std::string output;
  const int code = run_ctl(dome, {"leds", "--on", "9", "--hold-ms", "400"}, "ctl-leds", output);
  EXPECT_NE(code, 0) << output;
  EXPECT_NE(output.find("switched the LEDs off"), std::string::npos) << output;
  EXPECT_NE(output.find("max_on_us 50000"), std::string::npos) << output;

  // --json: one object naming the fault, and the same exit.
  const int json_code =
      run_ctl(dome, {"--json", "leds", "--on", "9", "--hold-ms", "400"}, "ctl-leds-json", output);
  EXPECT_NE(json_code, 0) << output;
  const auto open = output.find('{');
  const auto close = output.rfind('}');
  ASSERT_NE(open, std::string::npos) << output;
  const auto j = nlohmann::json::parse(output.substr(open, close - open + 1));
  ASSERT_TRUE(j.at("fault").is_string()) << j.dump();
  EXPECT_NE(j.at("fault").get<std::string>().find("LED 9"), std::string::npos) << j.dump();
  EXPECT_LT(j.at("held_ms").get<std::int64_t>(), 400);

  // A hold within the limit is no fault.
  EXPECT_EQ(run_ctl(dome, {"leds", "--on", "9", "--hold-ms", "20"}, "ctl-leds-short", output), 0) << output;
}

TEST(ControllerFaults, DaemonExitsWithItsGpioCodeWhenTheBackendIsLost) {
  SimulatedDome dome;
  {
    auto client = dome.connect();
    client->set_leds({{4, 1.0f}});
    dome.sim().signal(SIGKILL);  // the GPIO backend is gone
    ASSERT_TRUE(dome.sim().wait(5s).has_value());
    try {
      client->set_leds({{5, 1.0f}});
      FAIL() << "a command on a lost GPIO backend succeeded";
    } catch (const ControllerError& e) {
      EXPECT_EQ(e.code(), proto::Error::GPIO_ERROR) << e.what();
    }
  }
  const auto code = dome.firmware().wait(10s);
  ASSERT_TRUE(code.has_value()) << "lightstage-domed keeps running on a lost GPIO backend";
  EXPECT_EQ(*code, 4) << dome.logs();
  EXPECT_NE(dome.firmware().output().find("GPIO backend"), std::string::npos) << dome.firmware().output();
}

TEST(ControllerFaults, CheckWithAMissingChipExitsWithTheCheckCode) {
  const auto missing = socket_dir() / "no-such-sim.sock";
  ChildProcess check(bin_dir() / "lightstage-domed",
                     {"--rig", (source_dir() / "hw/rigs/sim-dome.yaml").string(), "--gpio",
                      "sim:" + missing.string(), "--check"},
                     scratch_dir() / "check.log");
  const auto code = check.wait(20s);
  ASSERT_TRUE(code.has_value());
  EXPECT_EQ(*code, 3) << check.output();
  EXPECT_NE(check.output().find("cannot open the chip"), std::string::npos) << check.output();
}

}  // namespace
}  // namespace lightstage::testing
