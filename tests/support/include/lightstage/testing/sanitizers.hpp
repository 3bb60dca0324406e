#pragma once
// Whether this test binary runs under AddressSanitizer. The sanitizer flavour
// exists to run every code path instrumented; figures measured over whole
// datasets (dozens of solves of a real capture) take it ten times longer and
// are measured by the optimised flavour, while a smaller test of the same
// code runs instrumented.

#include <gtest/gtest.h>

namespace lightstage::testing {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kUnderSanitizers = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kUnderSanitizers = true;
#else
inline constexpr bool kUnderSanitizers = false;
#endif
#else
inline constexpr bool kUnderSanitizers = false;
#endif

}  // namespace lightstage::testing

// Skips a dataset-wide measurement under the sanitizers; `covered_by` names
// the test that runs the same code instrumented.
#define LIGHTSTAGE_MEASURED_IN_RELEASE_ONLY(covered_by)                                               \
  do {                                                                                                \
    if (::lightstage::testing::kUnderSanitizers)                                                      \
      GTEST_SKIP() << "a dataset-wide measurement: the release flavour measures it; " << (covered_by) \
                   << " runs its code under the sanitizers";                                          \
  } while (false)
