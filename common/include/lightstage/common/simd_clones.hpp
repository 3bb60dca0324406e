#pragma once
// LIGHTSTAGE_SIMD_CLONES before a function built from vector-extension types
// wider than the baseline's registers: on x86-64 (GCC, Clang) it is built
// once for AVX2 and once for baseline x86-64, and the loader picks one at
// run time; elsewhere it is built once. AVX2 alone brings no fused
// multiply–add, so both builds round every lane alike. Not under
// AddressSanitizer: the loader runs the choice before the sanitizer is set
// up, and an instrumented choice crashes (google/sanitizers#342).

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define LIGHTSTAGE_SIMD_NO_CLONES
#endif
#endif
#if defined(__SANITIZE_ADDRESS__)
#define LIGHTSTAGE_SIMD_NO_CLONES
#endif
#if defined(__x86_64__) && defined(__has_attribute) && !defined(LIGHTSTAGE_SIMD_NO_CLONES)
#if __has_attribute(target_clones)
#define LIGHTSTAGE_SIMD_CLONES __attribute__((target_clones("avx2", "default")))
#endif
#endif
#ifndef LIGHTSTAGE_SIMD_CLONES
#define LIGHTSTAGE_SIMD_CLONES
#endif
