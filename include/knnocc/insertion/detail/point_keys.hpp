// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// point_keys8: KeyRounding::point_to_key for eight contiguous Point3f at once (AVX2), the key
// rounding of ScanInserter's chunked collect.
//
// The eight points are 24 floats: three 256-bit loads, shuffled into x, y and z vectors (no
// per-float stores: a vector load of data just stored float by float waits for the stores). Per
// coordinate the same double operations as KeyRounding::index: product with 1 / resolution, the
// range test, floor (exact), plus the centre index. Only when all eight points are finite and in
// the key range; otherwise the caller treats the eight one by one, which also counts them.

#include <cstdint>

#include "../../core/detail/simd_support.hpp"
#include "../../core/point3.hpp"

namespace knnocc::detail {

#if KNNOCC_AVX2_LANES

/// Keys of p[0..8) into key[axis][point] and true, or false (key unspecified) when a point is not
/// finite or outside [-center, center) voxels along an axis. inv_res: KeyRounding's 1 / resolution.
template <class Key>
__attribute__((target("avx2"))) bool point_keys8(const Point3f* p, double inv_res,
                                                 std::int32_t (&key)[3][8]) {
  static_assert(sizeof(Point3f) == 3 * sizeof(float), "Point3f is three packed floats");
  const float* f = &p[0].x;
  // Points 0-3 in the low 128 bits, 4-7 in the high: m03 = x0 y0 z0 x1 | x4 y4 z4 x5, and so on.
  const __m256 m03 =
      _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(f)), _mm_loadu_ps(f + 12), 1);
  const __m256 m14 =
      _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(f + 4)), _mm_loadu_ps(f + 16), 1);
  const __m256 m25 =
      _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(f + 8)), _mm_loadu_ps(f + 20), 1);
  const __m256 xy = _mm256_shuffle_ps(m14, m25, _MM_SHUFFLE(2, 1, 3, 2));  // x2 y2 x3 y3
  const __m256 yz = _mm256_shuffle_ps(m03, m14, _MM_SHUFFLE(1, 0, 2, 1));  // y0 z0 y1 z1
  const __m256 c[3] = {_mm256_shuffle_ps(m03, xy, _MM_SHUFFLE(2, 0, 3, 0)),
                       _mm256_shuffle_ps(yz, xy, _MM_SHUFFLE(3, 1, 2, 0)),
                       _mm256_shuffle_ps(yz, m25, _MM_SHUFFLE(3, 0, 3, 1))};
  constexpr auto center = static_cast<double>(Key::center);
  const __m256d scale = _mm256_set1_pd(inv_res), lo = _mm256_set1_pd(-center),
                hi = _mm256_set1_pd(center);
  __m256d ok = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
  for (int a = 0; a < 3; ++a)
    for (int h = 0; h < 2; ++h) {
      const __m256d s = _mm256_mul_pd(scale, _mm256_cvtps_pd(h ? _mm256_extractf128_ps(c[a], 1)
                                                               : _mm256_castps256_ps128(c[a])));
      // s >= -center && s < center, false for NaN (KeyRounding::index's test).
      ok = _mm256_and_pd(
          ok, _mm256_and_pd(_mm256_cmp_pd(s, lo, _CMP_GE_OQ), _mm256_cmp_pd(s, hi, _CMP_LT_OQ)));
      const __m128i k = _mm_add_epi32(_mm256_cvttpd_epi32(_mm256_floor_pd(s)),
                                      _mm_set1_epi32(static_cast<std::int32_t>(Key::center)));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(key[a] + 4 * h), k);
    }
  return _mm256_movemask_pd(ok) == 0xf;
}

#endif  // KNNOCC_AVX2_LANES

}  // namespace knnocc::detail
