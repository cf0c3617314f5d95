// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// OccupancyMap::update_brick's value updates: update_values_scalar voxel by voxel, and
// update_values_avx2 eight voxels at a time (AVX2) with the same results (a test compares them).
//
// Per voxel i of a brick with its bit in the mask: a voxel not known yet takes `fresh`; a known
// one stays where it is at the bound in delta's direction (OctoMap's early abort), and otherwise
// takes clamp(v + delta). The eight voxels of a mask byte go through the same float addition and
// the same comparisons, in vector form, and the voxels outside the mask keep their values. The
// clamp is two compare-and-blends like the scalar `v < min ? min : v > max ? max : v` (min/max
// instructions would differ on signed zeros). The arithmetic runs on all eight floats of the
// byte, masked voxels or not; the stores keep the unmasked ones bit for bit (a fresh brick's
// unused values may be anything, so with floating-point traps enabled, which knnocc never does,
// that arithmetic could trap). The known bits are the caller's to update.

#include <cstddef>
#include <cstdint>

#include "../../core/detail/simd_support.hpp"

namespace knnocc::detail {

/// One update's log-odds change, the value of a voxel seen for the first time, and the bounds.
struct ValueUpdate {
  float delta, fresh, clamp_min, clamp_max;
};

/// values[64 j + k] for every bit k of mask[j] (j < words), one voxel at a time.
inline void update_values_scalar(float* values, const std::uint64_t* mask,
                                 const std::uint64_t* known, std::size_t words,
                                 const ValueUpdate& u) {
  const bool up = u.delta >= 0, down = u.delta <= 0;
  for (std::size_t j = 0; j < words; ++j)
    for (std::uint64_t m = mask[j]; m; m &= m - 1) {
      const int bit = __builtin_ctzll(m);
      float& v = values[j * 64 + static_cast<std::size_t>(bit)];
      if (!((known[j] >> bit) & 1)) {
        v = u.fresh;
      } else if (!((up && v >= u.clamp_max) || (down && v <= u.clamp_min))) {
        const float s = v + u.delta;  // OctoMap's early abort at the bound, else add and clamp
        v = s < u.clamp_min ? u.clamp_min : (s > u.clamp_max ? u.clamp_max : s);
      }
    }
}

#if KNNOCC_AVX2_LANES

// The eight lanes whose bit is set in `byte`, as an all-ones/all-zeros mask.
__attribute__((target("avx2"))) inline __m256 byte_lanes(std::uint64_t byte) {
  const __m256i bit = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
  const __m256i b = _mm256_set1_epi32(static_cast<int>(byte));
  return _mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_and_si256(b, bit), bit));
}

/// update_values_scalar(), eight voxels of a mask byte at a time.
__attribute__((target("avx2"))) inline void update_values_avx2(float* values,
                                                               const std::uint64_t* mask,
                                                               const std::uint64_t* known,
                                                               std::size_t words,
                                                               const ValueUpdate& u) {
  const __m256 delta = _mm256_set1_ps(u.delta), fresh = _mm256_set1_ps(u.fresh),
               lo = _mm256_set1_ps(u.clamp_min), hi = _mm256_set1_ps(u.clamp_max);
  // At the bound: v >= max when delta >= 0, v <= min when delta <= 0 (both when delta is 0).
  const __m256 up = _mm256_castsi256_ps(_mm256_set1_epi32(u.delta >= 0 ? -1 : 0));
  const __m256 down = _mm256_castsi256_ps(_mm256_set1_epi32(u.delta <= 0 ? -1 : 0));
  for (std::size_t j = 0; j < words; ++j) {
    const std::uint64_t m = mask[j];
    if (!m) continue;
    for (int q = 0; q < 8; ++q) {
      const std::uint64_t byte = (m >> (8 * q)) & 0xff;
      if (!byte) continue;
      float* p = values + 64 * j + 8 * static_cast<std::size_t>(q);
      const __m256 v = _mm256_loadu_ps(p);
      const __m256 stuck = _mm256_or_ps(_mm256_and_ps(up, _mm256_cmp_ps(v, hi, _CMP_GE_OQ)),
                                        _mm256_and_ps(down, _mm256_cmp_ps(v, lo, _CMP_LE_OQ)));
      __m256 s = _mm256_add_ps(v, delta);
      s = _mm256_blendv_ps(s, lo, _mm256_cmp_ps(s, lo, _CMP_LT_OQ));
      s = _mm256_blendv_ps(s, hi, _mm256_cmp_ps(s, hi, _CMP_GT_OQ));
      const __m256 seen = _mm256_blendv_ps(s, v, stuck);
      const __m256 next = _mm256_blendv_ps(fresh, seen, byte_lanes((known[j] >> (8 * q)) & 0xff));
      _mm256_storeu_ps(p, _mm256_blendv_ps(v, next, byte_lanes(byte)));
    }
  }
}

#endif  // KNNOCC_AVX2_LANES

}  // namespace knnocc::detail
