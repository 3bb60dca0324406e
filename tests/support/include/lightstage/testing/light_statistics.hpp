#pragma once
// Per-light statistics two solves of the same stack recorded in summary.json
// (a whole solve against its bands or its merged tiles): the same threshold,
// pixels, counts, and the same means up to the order of their float sums.

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>

namespace lightstage::testing {

inline void expect_same_light_statistics(const nlohmann::json& expected, const nlohmann::json& actual) {
  ASSERT_TRUE(expected.contains("light_statistics"));
  ASSERT_TRUE(actual.contains("light_statistics"));
  const nlohmann::json& e = expected["light_statistics"];
  const nlohmann::json& a = actual["light_statistics"];
  for (const char* key : {"shadow_threshold", "threshold_source", "pixels"}) EXPECT_EQ(a[key], e[key]) << key;
  ASSERT_EQ(a["frames"].size(), e["frames"].size());
  for (std::size_t i = 0; i < e["frames"].size(); ++i) {
    const nlohmann::json& ef = e["frames"][i];
    const nlohmann::json& af = a["frames"][i];
    EXPECT_EQ(af["file"], ef["file"]);
    EXPECT_EQ(af["saturated_share"], ef["saturated_share"]) << ef["file"];
    EXPECT_EQ(af["shadow_share"], ef["shadow_share"]) << ef["file"];
    const double mean = ef["mean_value"].get<double>();
    EXPECT_NEAR(af["mean_value"].get<double>(), mean, 1e-12 * std::abs(mean)) << ef["file"];
  }
}

}  // namespace lightstage::testing
