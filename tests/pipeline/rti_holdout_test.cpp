// Leave-one-light-out relighting of the per-pixel RTI models on DiLiGenT's
// ball (skipped without the shared data): the figures docs/rti-formats.md
// reports, pinned loosely so a broken fit or evaluation shows.
#include "lightstage/pipeline/rti_exchange.hpp"
#include "lightstage/testing/paths.hpp"
#include "lightstage/testing/sanitizers.hpp"

#include <gtest/gtest.h>

namespace lightstage {
namespace {

TEST(RtiHoldout, BallMatchesThePublishedRtiFigures) {
  const auto ball = testing::shared_data_dir() / "diligent/ballPNG";
  if (testing::shared_data_dir().empty() || !std::filesystem::exists(ball))
    GTEST_SKIP() << "no DiLiGenT ball";
  const auto r =
      pipeline::rti_holdout({.input = ball, .held_out = 12, .methods = {}});  // the RTI models only
  ASSERT_EQ(r["held_out"].size(), 12u);
  // Issue 20 quotes 0.209 for PTM, HSH-3 and l2 on its protocol; measured 0.197 / 0.200 / 0.195.
  for (const char* model : {"ptm", "hsh2", "hsh3", "l2"}) {
    const double e = r["models"][model]["relative_rmse"].get<double>();
    EXPECT_GT(e, 0.15) << model;
    EXPECT_LT(e, 0.22) << model;
  }
}

// Issue 20: a solve's reflectance relights held-out lights better than the
// per-pixel RTI fits (relighting_fit.hpp; 1.257 before the refit, 0.1888
// with the polynomial alone, 0.1503 with the specular lobe). Twelve full
// solves of the ball: measured in the optimised flavour only, the fit's code
// runs under the sanitizers in test_host_relighting_fit.
class RtiHoldoutMethod : public ::testing::TestWithParam<const char*> {};

TEST_P(RtiHoldoutMethod, BallRelightsBetterThanPtmAndHsh) {
  const auto ball = testing::shared_data_dir() / "diligent/ballPNG";
  if (testing::shared_data_dir().empty() || !std::filesystem::exists(ball))
    GTEST_SKIP() << "no DiLiGenT ball";
  LIGHTSTAGE_MEASURED_IN_RELEASE_ONLY("test_host_relighting_fit");
  const std::string method = GetParam();
  const auto r = pipeline::rti_holdout({.input = ball, .held_out = 12, .methods = {method}});
  const double e = r["models"][method]["relative_rmse"].get<double>();
  RecordProperty("relative_rmse", std::to_string(e));
  for (const char* model : {"ptm", "hsh2", "hsh3"})
    EXPECT_LT(e, r["models"][model]["relative_rmse"].get<double>()) << method << " against " << model;
  EXPECT_LT(e, 0.155) << method;  // measured 0.1503
}

INSTANTIATE_TEST_SUITE_P(SolveMethods, RtiHoldoutMethod, ::testing::Values("biquadratic", "auto"));

}  // namespace
}  // namespace lightstage
