#pragma once
// Sorting several short lists at once, one list per SIMD lane.
//
// Batcher's odd–even merge sort is a fixed sequence of compare–exchanges,
// the same whatever the values, so it runs on kLanes lists side by side as a
// min and a max of vectors per exchange, with no branch. For a pixel's few
// dozen values (per-pixel medians) that sorts eight lists in the time
// select_kth takes to find the median of about two to four of them where the
// CPU has 8-float vectors (x86-64 with AVX2, chosen at run time); elsewhere
// about in the time of one each. bench_photometric measures it.

#include <cstddef>
#include <cstdint>
#include <vector>

namespace lightstage {

class LaneSort {
 public:
  static constexpr std::size_t kLanes = 8;

  // Lists of up to `max_length` values.
  explicit LaneSort(std::size_t max_length);

  // How many values each lane of a sort() holds when its longest list has
  // `longest` values: `longest` rounded up to whole networks (a few more).
  std::size_t slots(std::size_t longest) const;

  // Sorts each lane of values[0, slots × kLanes) ascending, where
  // values[i × kLanes + lane] is the lane's i-th value and `slots` came from
  // slots(). A shorter list pads its lane with +infinity, which stays behind
  // its values. NaN-free. Not thread-safe (it builds networks as it needs
  // them): one per thread.
  void sort(float* values, std::size_t slots);

 private:
  static constexpr std::size_t kStep = 8;  // networks for lengths 8, 16, 24, …
  std::size_t max_length_;
  // [length / kStep − 1]: the exchanges' slot pairs, flat; empty until used.
  std::vector<std::vector<std::uint16_t>> networks_;
};

}  // namespace lightstage
