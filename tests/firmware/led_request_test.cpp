#include "lightstage/firmware/led_request.hpp"

#include "support/test_rigs.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <utility>
#include <vector>

namespace lightstage::firmware {
namespace {

using ::testing::Optional;

google::protobuf::RepeatedPtrField<proto::LedLevel> levels(
    std::vector<std::pair<std::uint32_t, float>> leds) {
  google::protobuf::RepeatedPtrField<proto::LedLevel> out;
  for (const auto& [id, level] : leds) {
    proto::LedLevel* led = out.Add();
    led->set_led_id(id);
    led->set_level(level);
  }
  return out;
}

TEST(LedRequest, AcceptsKnownLedsAtZeroOrOne) {
  const Rig rig = testing::direct_rig();
  EXPECT_FALSE(led_levels_problem(rig, levels({})));
  EXPECT_FALSE(led_levels_problem(rig, levels({{0, 1.0F}, {2, 0.0F}, {3, 1.0F}})));
  EXPECT_FALSE(led_levels_problem(rig, levels({{1, 1.0F}}), 4));
}

TEST(LedRequest, NamesTheProblemForSetLeds) {
  const Rig rig = testing::direct_rig();
  EXPECT_THAT(led_levels_problem(rig, levels({{0, 1.0F}, {7, 1.0F}})),
              Optional(std::string("rig 'direct-4' has no LED 7")));
  EXPECT_THAT(led_levels_problem(rig, levels({{1, 1.0F}, {1, 0.0F}})),
              Optional(std::string("LED 1 listed twice")));
  EXPECT_THAT(led_levels_problem(rig, levels({{2, 1.5F}})),
              Optional(std::string("LED 2: level 1.5 outside 0..1")));
  EXPECT_THAT(led_levels_problem(rig, levels({{2, -1.0F}})),
              Optional(std::string("LED 2: level -1 outside 0..1")));
  EXPECT_THAT(led_levels_problem(rig, levels({{3, 0.5F}})),
              Optional(std::string("LED 3: level 0.5: these LED drivers cannot dim (levels are 0 or 1)")));
}

TEST(LedRequest, NamesTheStepForASequence) {
  const Rig rig = testing::direct_rig();
  EXPECT_THAT(led_levels_problem(rig, levels({{7, 1.0F}}), 2),
              Optional(std::string("step 2: rig 'direct-4' has no LED 7")));
  EXPECT_THAT(led_levels_problem(rig, levels({{1, 1.0F}, {1, 1.0F}}), 0),
              Optional(std::string("step 0: LED 1 listed twice")));
  EXPECT_THAT(led_levels_problem(rig, levels({{2, 2.0F}}), 5),
              Optional(std::string("step 5: LED 2 level 2 outside 0..1")));
  EXPECT_THAT(
      led_levels_problem(rig, levels({{3, 0.25F}}), 1),
      Optional(std::string("step 1: LED 3 level 0.25: these LED drivers cannot dim (levels are 0 or 1)")));
}

TEST(LedRequest, RefusesANanLevel) {
  const Rig rig = testing::direct_rig();
  const auto problem = led_levels_problem(rig, levels({{0, std::numeric_limits<float>::quiet_NaN()}}));
  ASSERT_TRUE(problem);
  EXPECT_THAT(*problem, ::testing::HasSubstr("outside 0..1"));
}

TEST(LedRequest, ReportsTheFirstProblemInListOrder) {
  const Rig rig = testing::direct_rig();
  // LED 0 is dimmed before the unknown LED 9 comes up.
  EXPECT_THAT(led_levels_problem(rig, levels({{0, 0.5F}, {9, 1.0F}})),
              Optional(std::string("LED 0: level 0.5: these LED drivers cannot dim (levels are 0 or 1)")));
}

}  // namespace
}  // namespace lightstage::firmware
