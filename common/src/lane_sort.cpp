#include "lightstage/common/lane_sort.hpp"

#include "lightstage/common/error.hpp"
#include "lightstage/common/simd_clones.hpp"

#include <cstring>

namespace lightstage {
namespace {

// Batcher's odd–even merge sort of the power of two at or above `length`,
// less every exchange that touches a slot at or past `length`: those slots
// hold +infinity, which no exchange moves down, so such an exchange never
// swaps.
// Each exchange is two slots, lower then higher, one after the other.
std::vector<std::uint16_t> odd_even_merge_network(std::size_t length) {
  std::size_t size = 1;
  while (size < length) size <<= 1;
  std::vector<std::uint16_t> out;
  for (std::size_t run = 1; run < size; run <<= 1) {
    for (std::size_t gap = run; gap >= 1; gap >>= 1) {
      for (std::size_t start = gap % run; start + gap < size; start += 2 * gap) {
        for (std::size_t i = 0; i < gap && start + i + gap < size; ++i) {
          const std::size_t low = start + i, high = low + gap;
          // Only within one pair of runs being merged.
          if (low / (2 * run) != high / (2 * run) || high >= length) continue;
          out.push_back(static_cast<std::uint16_t>(low));
          out.push_back(static_cast<std::uint16_t>(high));
        }
      }
    }
  }
  return out;
}

using Lanes = float __attribute__((vector_size(LaneSort::kLanes * sizeof(float))));

LIGHTSTAGE_SIMD_CLONES void run_network(const std::uint16_t* exchange, const std::uint16_t* end,
                                        float* values) {
  constexpr std::size_t kLanes = LaneSort::kLanes;
  for (; exchange != end; exchange += 2) {
    float* low = values + exchange[0] * kLanes;
    float* high = values + exchange[1] * kLanes;
    Lanes a, b;
    std::memcpy(&a, low, sizeof a);
    std::memcpy(&b, high, sizeof b);
    const auto less = a < b;
    const Lanes smaller = less ? a : b, larger = less ? b : a;
    std::memcpy(low, &smaller, sizeof smaller);
    std::memcpy(high, &larger, sizeof larger);
  }
}

}  // namespace

LaneSort::LaneSort(std::size_t max_length)
    : max_length_(max_length), networks_((max_length + kStep - 1) / kStep) {
  if (max_length > 65536) fail("LaneSort: lists of {} values, at most 65536", max_length);
}

std::size_t LaneSort::slots(std::size_t longest) const {
  if (longest > max_length_) fail("LaneSort: a list of {} values, made for at most {}", longest, max_length_);
  return (longest + kStep - 1) / kStep * kStep;
}

void LaneSort::sort(float* values, std::size_t slots) {
  if (slots == 0) return;
  if (slots % kStep != 0 || slots / kStep > networks_.size())
    fail("LaneSort: {} slots, not a length from slots()", slots);
  // Built the first time a length is sorted: a pixel's lists are mostly far
  // shorter than the frame count.
  std::vector<std::uint16_t>& network = networks_[slots / kStep - 1];
  if (network.empty()) network = odd_even_merge_network(slots);
  run_network(network.data(), network.data() + network.size(), values);
}

}  // namespace lightstage
