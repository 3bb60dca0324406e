// The host's check that the controller runs its --rig: by name, and by content
// when the controller reports a fingerprint.
#include "lightstage/pipeline/dome_connection.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/rig_fingerprint.hpp"
#include "lightstage/testing/paths.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

namespace lightstage::pipeline {
namespace {

using ::testing::HasSubstr;

std::string error_of(const Rig& rig, const proto::Info& info) {
  try {
    check_same_rig(rig, "host.yaml", info);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

proto::Info info_of(const Rig& rig) {
  proto::Info info;
  info.set_rig_name(rig.name);
  info.set_rig_fingerprint(rig_fingerprint(rig));
  return info;
}

std::string sim_dome_text() {
  std::ifstream in(testing::source_dir() / "hw/rigs/sim-dome.yaml");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(DomeConnection, TheSameRigIsAccepted) {
  const Rig rig = load_rig(testing::source_dir() / "hw/rigs/sim-dome.yaml");
  EXPECT_EQ(error_of(rig, info_of(rig)), "");
  // Comments and blank lines are no difference.
  const Rig commented = parse_rig("# a copy\n\n" + sim_dome_text() + "\n# end\n", "copy.yaml");
  EXPECT_EQ(error_of(commented, info_of(rig)), "");
}

TEST(DomeConnection, ARigOfTheSameNameButOtherContentIsRefused) {
  const std::string text = sim_dome_text();
  const Rig host = parse_rig(text, "host.yaml");
  // The controller's copy differs only in its default on-time limit.
  std::string controller_text = text;
  const auto at = controller_text.find("max_on_us: 2000000");
  ASSERT_NE(at, std::string::npos);
  controller_text.replace(at, 18, "max_on_us: 1234");
  const Rig controller = parse_rig(controller_text, "controller.yaml");
  ASSERT_EQ(controller.name, host.name);
  const std::string message = error_of(host, info_of(controller));
  EXPECT_THAT(message,
              HasSubstr("--rig 'host.yaml' and the controller's rig are both named 'sim-dome' but differ"));
  EXPECT_THAT(message, HasSubstr(rig_fingerprint(host)));
  EXPECT_THAT(message, HasSubstr(rig_fingerprint(controller)));
}

TEST(DomeConnection, AnotherNameIsRefusedAndShownEscaped) {
  const Rig rig = load_rig(testing::source_dir() / "hw/rigs/sim-dome.yaml");
  proto::Info info = info_of(rig);
  info.set_rig_name("evil\x1b[2J");
  const std::string message = error_of(rig, info);
  EXPECT_THAT(message, HasSubstr("the controller runs rig 'evil\\x1b[2J'"));
  EXPECT_EQ(message.find('\x1b'), std::string::npos);
}

TEST(DomeConnection, AControllerWithoutFingerprintsIsComparedByName) {
  const Rig rig = load_rig(testing::source_dir() / "hw/rigs/sim-dome.yaml");
  proto::Info info;
  info.set_rig_name(rig.name);
  EXPECT_EQ(error_of(rig, info), "");
}

}  // namespace
}  // namespace lightstage::pipeline
