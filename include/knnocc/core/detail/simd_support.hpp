// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Which vector code paths this build has, and whether the CPU can run them: KNNOCC_AVX2_LANES
// (x86-64 with GCC or clang, unless KNNOCC_NO_SIMD is defined), and cpu_has_avx2() and
// cpu_has_avx512(), run-time checks. The vector code itself is in the headers named after what it
// computes (raycast/detail/walk_avx2.hpp and walk_avx512.hpp, insertion/detail/point_keys.hpp,
// map/detail/brick_values.hpp); elsewhere they fall back to scalar code with the same results.

#if !defined(KNNOCC_NO_SIMD) && (defined(__GNUC__) || defined(__clang__)) && defined(__x86_64__)
#define KNNOCC_AVX2_LANES 1
#include <immintrin.h>
#else
#define KNNOCC_AVX2_LANES 0
#endif

namespace knnocc::detail {

#if KNNOCC_AVX2_LANES
/// AVX2 and BMI2 (the lane walk's shifts), known at compile time or checked once at run time.
inline bool cpu_has_avx2() {
#if defined(__AVX2__) && defined(__BMI2__)
  return true;
#else
  static const bool has = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("bmi2");
  return has;
#endif
}

/// AVX-512F (and BMI2), known at compile time or checked once at run time.
inline bool cpu_has_avx512() {
#if defined(__AVX512F__) && defined(__BMI2__)
  return true;
#else
  static const bool has = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("bmi2");
  return has;
#endif
}
#endif

}  // namespace knnocc::detail
