#include "lightstage/common/select_kth.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace lightstage {
namespace {

// Against std::nth_element on arrays with few distinct values (many ties) and with none.
template <typename T>
void agrees_with_nth_element() {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 3000; ++trial) {
    const int n = 1 + static_cast<int>(rng() % 40);
    const bool ties = trial % 2 == 0;
    std::uniform_int_distribution<int> few(0, 3);
    std::normal_distribution<T> many;
    std::vector<T> values(static_cast<std::size_t>(n));
    for (T& v : values) v = ties ? static_cast<T>(few(rng)) : many(rng);
    for (int k = 0; k < n; ++k) {
      std::vector<T> ours = values, reference = values;
      std::nth_element(reference.begin(), reference.begin() + k, reference.end());
      ASSERT_EQ(select_kth(ours.data(), n, k), reference[static_cast<std::size_t>(k)])
          << "n " << n << " k " << k;
      // Only reordered.
      std::sort(ours.begin(), ours.end());
      std::sort(reference.begin(), reference.end());
      ASSERT_EQ(ours, reference);
    }
  }
}

TEST(SelectKth, AgreesWithNthElementOnEveryRankOfRandomArrays) {
  agrees_with_nth_element<double>();
  agrees_with_nth_element<float>();
}

TEST(SelectKth, HandlesOneValueAndAllEqual) {
  double one[] = {4.5};
  EXPECT_EQ(select_kth(one, 1, 0), 4.5);
  std::vector<double> equal(96, 0.25);
  EXPECT_EQ(select_kth(equal.data(), 96, 48), 0.25);
  // The smallest value repeated below a few larger ones, the k-th among or beyond them.
  std::vector<float> floor_and_more(90, 0.5f);
  floor_and_more[10] = 2;
  floor_and_more[40] = 1;
  std::vector<float> copy = floor_and_more;
  EXPECT_EQ(select_kth(copy.data(), 90, 45), 0.5f);
  copy = floor_and_more;
  EXPECT_EQ(select_kth(copy.data(), 90, 88), 1.0f);
  copy = floor_and_more;
  EXPECT_EQ(select_kth(copy.data(), 90, 89), 2.0f);
  double sorted[] = {1, 2, 3, 4, 5}, reversed[] = {5, 4, 3, 2, 1};
  EXPECT_EQ(select_kth(sorted, 5, 2), 3);
  EXPECT_EQ(select_kth(reversed, 5, 4), 5);
}

}  // namespace
}  // namespace lightstage
