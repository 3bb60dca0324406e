#include "lightstage/common/lane_sort.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>
#include <vector>

namespace lightstage {
namespace {

constexpr std::size_t kLanes = LaneSort::kLanes;
constexpr float kInfinity = std::numeric_limits<float>::infinity();

// Every length up to 200, each lane its own length, with ties and without:
// each lane comes out as std::sort orders its list, the padding after it.
TEST(LaneSort, SortsEveryLaneAsStdSortDoes) {
  LaneSort sorter(200);
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> few(0, 3);
  std::normal_distribution<float> many;
  for (std::size_t longest = 0; longest <= 200; ++longest) {
    for (const bool ties : {true, false}) {
      std::vector<std::vector<float>> lists(kLanes);
      std::size_t slots_needed = 0;
      for (std::size_t lane = 0; lane < kLanes; ++lane) {
        const std::size_t length = lane == 0 ? longest : rng() % (longest + 1);
        for (std::size_t i = 0; i < length; ++i)
          lists[lane].push_back(ties ? static_cast<float>(few(rng)) : many(rng));
        slots_needed = std::max(slots_needed, length);
      }
      const std::size_t slots = sorter.slots(slots_needed);
      ASSERT_GE(slots, longest);
      ASSERT_LT(slots, longest + 8);
      std::vector<float> values(slots * kLanes, kInfinity);
      for (std::size_t lane = 0; lane < kLanes; ++lane)
        for (std::size_t i = 0; i < lists[lane].size(); ++i) values[i * kLanes + lane] = lists[lane][i];
      sorter.sort(values.data(), slots);
      for (std::size_t lane = 0; lane < kLanes; ++lane) {
        std::vector<float> expected = lists[lane];
        std::sort(expected.begin(), expected.end());
        expected.resize(slots, kInfinity);
        for (std::size_t i = 0; i < slots; ++i)
          ASSERT_EQ(values[i * kLanes + lane], expected[i])
              << "longest " << longest << " lane " << lane << " slot " << i;
      }
    }
  }
}

TEST(LaneSort, RefusesListsLongerThanItWasMadeFor) {
  LaneSort sorter(96);
  EXPECT_EQ(sorter.slots(96), 96u);
  EXPECT_EQ(sorter.slots(90), 96u);
  EXPECT_EQ(sorter.slots(0), 0u);
  EXPECT_THROW(sorter.slots(97), std::exception);
  std::vector<float> values(104 * kLanes);
  EXPECT_THROW(sorter.sort(values.data(), 104), std::exception);
  EXPECT_THROW(sorter.sort(values.data(), 12), std::exception);
}

}  // namespace
}  // namespace lightstage
