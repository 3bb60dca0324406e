// The CLI as a user meets it: help, version, the rig command.
#include "lightstage/testing/paths.hpp"
#include "lightstage/testing/run.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>

namespace lightstage {
namespace {

using testing::run_lightstage;

TEST(Cli, HelpListsEveryCommand) {
  const auto result = run_lightstage({"--help"});
  EXPECT_EQ(result.exit_code, 0) << result.err;
  for (const char* command : {"demo", "simulate", "solve", "eval", "rig"}) {
    EXPECT_NE(result.out.find(command), std::string::npos) << command << "\n" << result.out;
  }
}

TEST(Cli, EachCommandHasHelpWithAnExample) {
  for (const char* command : {"demo", "simulate", "solve", "eval", "rig"}) {
    const auto result = run_lightstage({command, "--help"});
    EXPECT_EQ(result.exit_code, 0) << command << result.err;
    EXPECT_NE(result.out.find("Example"), std::string::npos) << command << "\n" << result.out;
  }
}

TEST(Cli, VersionNamesTheBackends) {
  const auto result = run_lightstage({"--version"});
  EXPECT_EQ(result.exit_code, 0);
  EXPECT_NE(result.out.find("lightstage 0."), std::string::npos) << result.out;
  EXPECT_NE(result.out.find("gpiod:"), std::string::npos) << result.out;
}

TEST(Cli, RigListsEveryLed) {
  const auto result = run_lightstage({"rig", "--list"});
  EXPECT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.out.find("96 LEDs"), std::string::npos) << result.out;
  EXPECT_EQ(std::count(result.out.begin(), result.out.end(), '\n'), 1 + 1 + 96) << result.out;
}

TEST(Cli, BadRigIsOneLineNamingTheFile) {
  const auto dir = testing::scratch_dir();
  const auto rig = dir / "bad-rig.yaml";
  std::ofstream(rig) << "name: x\ndome_radius_mm: -3\n";
  const auto result = run_lightstage({"rig", "--rig", rig.string()});
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_NE(result.err.find("bad-rig.yaml:2"), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("dome_radius_mm"), std::string::npos) << result.err;
  EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
}

TEST(Cli, UnknownCommandFails) {
  const auto result = run_lightstage({"frobnicate"});
  EXPECT_NE(result.exit_code, 0);
}

}  // namespace
}  // namespace lightstage
