#pragma once
// Order statistics of a pixel's few dozen values (per-pixel medians).

#include <cstddef>
#include <utility>

namespace lightstage {

// The k-th smallest (0-based) of values[0, n), n ≥ 1, reordering them:
// quickselect whose partition (Lomuto's) moves every value whatever the
// comparison says, so its inner loop has no branch to mispredict. On a
// pixel's few dozen values std::nth_element spends most of its time
// mispredicting; this is about 3× faster there. A pivot that is its range's
// smallest value sets aside every value equal to it in one more pass, so
// ties (exact synthetic data, a clipped channel) stay linear. NaN-free input.
template <typename T>
T select_kth(T* values, std::ptrdiff_t n, std::ptrdiff_t k) {
  std::ptrdiff_t low = 0, high = n - 1;
  while (high > low) {
    // The median of three, as the pivot, at `high`.
    const std::ptrdiff_t middle = low + (high - low) / 2;
    if (values[middle] < values[low]) std::swap(values[middle], values[low]);
    if (values[high] < values[low]) std::swap(values[high], values[low]);
    if (values[middle] < values[high]) std::swap(values[middle], values[high]);
    const T pivot = values[high];
    // values[low, store) < pivot <= values[store, i).
    std::ptrdiff_t store = low;
    for (std::ptrdiff_t i = low; i < high; ++i) {
      const T value = values[i];
      values[i] = values[store];
      values[store] = value;
      store += value < pivot ? 1 : 0;
    }
    std::swap(values[store], values[high]);
    if (k == store) return pivot;
    if (k < store) {
      high = store - 1;
    } else if (store > low) {
      low = store + 1;
    } else {
      // Nothing was below the pivot: gather its equals, values[low, equal) == pivot < values[equal, high].
      std::ptrdiff_t equal = low + 1;
      for (std::ptrdiff_t i = low + 1; i <= high; ++i) {
        const T value = values[i];
        values[i] = values[equal];
        values[equal] = value;
        equal += value == pivot ? 1 : 0;
      }
      if (k < equal) return pivot;
      low = equal;
    }
  }
  return values[low];
}

}  // namespace lightstage
