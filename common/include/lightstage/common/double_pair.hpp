#pragma once
// Two doubles in one vector register (SSE2 on x86-64, NEON on arm64, both
// always there): sums over a pixel's lights two lights at a time, in the
// compilers' vector extension (GCC, Clang). A comparison gives a lane mask,
// and `mask ? a : b` picks lane by lane without a branch.

#include <cstring>

namespace lightstage {

using DoublePair = double __attribute__((vector_size(2 * sizeof(double))));
using FloatPair = float __attribute__((vector_size(2 * sizeof(float))));

inline DoublePair load_pair(const double* values) {
  DoublePair out;
  std::memcpy(&out, values, sizeof out);
  return out;
}

// Two floats, widened.
inline DoublePair load_pair(const float* values) {
  FloatPair out;
  std::memcpy(&out, values, sizeof out);
  return __builtin_convertvector(out, DoublePair);
}

inline double lane_sum(const DoublePair pair) { return pair[0] + pair[1]; }

}  // namespace lightstage
