// The real lightstage-domed reports its rig's content fingerprint, and a host
// holding another rig of the same name is refused before anything runs.
#include "dome_fixture.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/rig_fingerprint.hpp"
#include "lightstage/pipeline/dome_connection.hpp"
#include "lightstage/testing/paths.hpp"

#include <gtest/gtest.h>

namespace lightstage::testing {
namespace {

TEST(RigIdentityIntegration, AHostWithAnotherRigOfTheSameNameIsRefused) {
  const auto original_path = source_dir() / "hw/rigs/sim-dome.yaml";
  const auto tight_path =
      rig_with_limits(original_path, 50'000, 0.2, 1'000'000, scratch_dir() / "tight.yaml");
  const Rig original = load_rig(original_path);
  const Rig tight = load_rig(tight_path);
  ASSERT_EQ(original.name, tight.name);

  SimulatedDome dome({tight_path, {}, {}});
  auto client = dome.connect();
  const proto::Info& info = client->info();
  EXPECT_EQ(info.rig_fingerprint(), rig_fingerprint(tight));
  EXPECT_NO_THROW(pipeline::check_same_rig(tight, tight_path, info));
  try {
    pipeline::check_same_rig(original, original_path, info);
    FAIL() << "a rig with other limits but the same name was taken for the controller's";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("both named 'sim-dome' but differ"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace lightstage::testing
