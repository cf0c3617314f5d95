// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// AVX2 code of the dense walks (x86-64, checked at run time): eight rays set up at once, and four
// rays walked at once, one per 64-bit lane, with walk_ray()'s comparisons in branch-free form (the
// same comparisons on the same doubles, so exactly the same voxels; never FMA). The scalar walk
// spends most of its time on one branch, which axis steps next: a coin flip for the CPU's
// predictor. The four lanes test for ends only in the steps where a lane can end (unchecked_steps,
// end_point_clear): the last one for a ray with a clear end, the last four otherwise. A lane whose
// ray ends takes the next ray of the stream; when the stream runs dry the remaining rays finish on
// the scalar walk. Precondition: a box of fewer than 2^16 + 64 voxels per edge (ScanInserter's
// dense box), which bounds a ray's rounding error and the voxel indices converted through doubles.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>

#include "../../core/config.hpp"
#include "../../core/detail/simd_support.hpp"
#include "linear_ray.hpp"
#include "ray_block.hpp"

namespace knnocc::detail {

template <int Lanes>
struct LaneBook {
  std::int64_t iteration = 0;  // steps taken by every lane
  std::int64_t due[Lanes];     // value of `iteration` when a lane's step countdown runs out
  std::int64_t safe[Lanes];    // up to this value of `iteration` a lane cannot end

  KNNOCC_ALWAYS_INLINE void load(int l, const LinearRay& r) {
    due[l] = iteration + r.state.steps_to_end;
    // A clear end: only the last step, onto the end voxel, needs the test.
    safe[l] = iteration + (r.clear_end ? r.state.steps_to_end - 1 : unchecked_steps(r.state));
  }
  /// Steps every lane can take from here without an end test.
  KNNOCC_ALWAYS_INLINE std::int64_t unchecked() const {
    std::int64_t s = safe[0];
    for (int l = 1; l < Lanes; ++l) s = std::min(s, safe[l]);
    return s - iteration;
  }
};

#if KNNOCC_AVX2_LANES

#define KNNOCC_TARGET_AVX2 __attribute__((target("avx2,bmi2")))

// setup_linear_ray() for eight rays at once, into entries at .. at + 7 of a RayBlock (at a
// multiple of 8): setup_walk()'s float and double operations in the same order (square root,
// divisions and conversions are correctly rounded in SIMD as in scalar code), so the same bits;
// a test compares the two. The float part (direction, length) is eight lanes wide, the double
// part in two halves whose divisions overlap, the integer part (steps, strides, end voxel's
// index) in vector registers too.
template <class Key>
KNNOCC_TARGET_AVX2 void setup_linear_rays8(const RayFan& fan, const RayEnd* rays, RayBlock& out,
                                           std::size_t at) {
  alignas(32) float e[3][8];
  alignas(32) std::int32_t key[3][8];
  for (int k = 0; k < 8; ++k) {
    e[0][k] = rays[k].end.x;
    e[1][k] = rays[k].end.y;
    e[2][k] = rays[k].end.z;
    for (int a = 0; a < 3; ++a) key[a][k] = rays[k].key[a];
  }
  const float o[3] = {fan.origin.x, fan.origin.y, fan.origin.z};
  __m256 dir[3];
  for (int a = 0; a < 3; ++a) dir[a] = _mm256_sub_ps(_mm256_load_ps(e[a]), _mm256_set1_ps(o[a]));
  // octomap_norm: float squares summed left to right, square root in double, back to float.
  const __m256 sq =
      _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dir[0], dir[0]), _mm256_mul_ps(dir[1], dir[1])),
                    _mm256_mul_ps(dir[2], dir[2]));
  const __m256 length = _mm256_set_m128(
      _mm256_cvtpd_ps(_mm256_sqrt_pd(_mm256_cvtps_pd(_mm256_extractf128_ps(sq, 1)))),
      _mm256_cvtpd_ps(_mm256_sqrt_pd(_mm256_cvtps_pd(_mm256_castps256_ps128(sq)))));
  alignas(32) std::int32_t steps[8];
  const __m256d zero = _mm256_setzero_pd(),
                none = _mm256_set1_pd(std::numeric_limits<double>::max());
  // The end voxel's bit index is an integer below 2^51 (box edges under 2^17), exact in double,
  // and x + 1.5 * 2^52 holds x in its low mantissa bits: the conversion to int64 AVX2 lacks.
  const __m256d magic = _mm256_set1_pd(6755399441055744.0);
  __m256d index[2] = {zero, zero};
  __m256i step_sum = _mm256_setzero_si256();
  for (int a = 0; a < 3; ++a) {
    const __m256 d8 = _mm256_div_ps(dir[a], length);
    const __m256i k8 = _mm256_load_si256(reinterpret_cast<const __m256i*>(key[a]));
    step_sum = _mm256_add_epi32(
        step_sum, _mm256_abs_epi32(_mm256_sub_epi32(k8, _mm256_set1_epi32(fan.origin_key[a]))));
    const __m256i from_lo = _mm256_sub_epi32(k8, _mm256_set1_epi32(static_cast<int>(fan.lo[a])));
    const __m256d fan_stride = _mm256_set1_pd(static_cast<double>(fan.stride[a]));
    const __m256i plus = _mm256_set1_epi64x(fan.stride[a]),
                  minus = _mm256_set1_epi64x(-fan.stride[a]);
    for (int h = 0; h < 2; ++h) {
      const __m256d dd =
          _mm256_cvtps_pd(h ? _mm256_extractf128_ps(d8, 1) : _mm256_castps256_ps128(d8));
      const __m256d up = _mm256_cmp_pd(dd, zero, _CMP_GT_OQ);
      const __m256d down = _mm256_cmp_pd(dd, zero, _CMP_LT_OQ);
      // Step 0 (t_max and t_delta stay at max) where the direction is neither > 0 nor < 0: zero,
      // or NaN when the length underflowed (end points 1e-23 apart across a voxel border).
      const __m256d still = _mm256_cmp_pd(dd, zero, _CMP_EQ_UQ);
      const __m256d border =
          _mm256_blendv_pd(_mm256_set1_pd(fan.border[a][0]), _mm256_set1_pd(fan.border[a][1]), up);
      const __m256d tm =
          _mm256_div_pd(_mm256_sub_pd(border, _mm256_set1_pd(static_cast<double>(o[a]))), dd);
      const __m256d abs_d = _mm256_andnot_pd(_mm256_set1_pd(-0.0), dd);
      const __m256d td = _mm256_div_pd(_mm256_set1_pd(fan.resolution), abs_d);
      _mm256_store_pd(out.t_max[a] + at + 4 * h, _mm256_blendv_pd(tm, none, still));
      _mm256_store_pd(out.t_delta[a] + at + 4 * h, _mm256_blendv_pd(td, none, still));
      // stride: +-fan.stride by the sign of the float direction, 0 where it is neither.
      const __m256i s = _mm256_or_si256(_mm256_and_si256(_mm256_castpd_si256(up), plus),
                                        _mm256_and_si256(_mm256_castpd_si256(down), minus));
      _mm256_store_si256(reinterpret_cast<__m256i*>(out.stride[a] + at + 4 * h), s);
      const __m128i half =
          h ? _mm256_extracti128_si256(from_lo, 1) : _mm256_castsi256_si128(from_lo);
      index[h] = _mm256_add_pd(index[h], _mm256_mul_pd(_mm256_cvtepi32_pd(half), fan_stride));
    }
  }
  // end_point_clear(), operation for operation.
  const __m256d inv_res = _mm256_set1_pd(fan.inv_resolution), one = _mm256_set1_pd(1.0);
  unsigned clear = 0;
  for (int h = 0; h < 2; ++h) {
    const __m256i bits = _mm256_castpd_si256(_mm256_add_pd(index[h], magic));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out.end_index + at + 4 * h),
                        _mm256_sub_epi64(bits, _mm256_castpd_si256(magic)));
    const __m256d ld =
        _mm256_cvtps_pd(h ? _mm256_extractf128_ps(length, 1) : _mm256_castps256_ps128(length));
    _mm256_storeu_pd(out.length + at + 4 * h, ld);
    const __m256d margin = _mm256_add_pd(
        _mm256_mul_pd(_mm256_set1_pd(1e-5), _mm256_mul_pd(ld, inv_res)), _mm256_set1_pd(1e-3));
    const __m256d inner = _mm256_sub_pd(one, margin);
    __m256d ok = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
    for (int a = 0; a < 3; ++a) {
      const __m256d ed = _mm256_cvtps_pd(_mm_load_ps(e[a] + 4 * h));
      const __m128i k4 =
          _mm_sub_epi32(_mm_load_si128(reinterpret_cast<const __m128i*>(key[a] + 4 * h)),
                        _mm_set1_epi32(static_cast<std::int32_t>(Key::center)));
      const __m256d f = _mm256_sub_pd(_mm256_mul_pd(inv_res, ed), _mm256_cvtepi32_pd(k4));
      ok = _mm256_and_pd(ok, _mm256_and_pd(_mm256_cmp_pd(f, margin, _CMP_GT_OQ),
                                           _mm256_cmp_pd(f, inner, _CMP_LT_OQ)));
    }
    clear |= static_cast<unsigned>(_mm256_movemask_pd(ok)) << (4 * h);
  }
  _mm256_store_si256(reinterpret_cast<__m256i*>(steps), step_sum);
  const std::int64_t origin_index = fan.index(fan.origin_key);
  for (int k = 0; k < 8; ++k) {
    const std::size_t i = at + static_cast<std::size_t>(k);
    const bool clear_end = (clear >> k) & 1u;
    out.index[i] = origin_index;
    out.steps_to_end[i] = steps[k];
    out.clear_end[i] = clear_end;
    out.lane_steps[i] = RayBlock::lane_steps_of(steps[k], clear_end);
  }
}

// ---- four lanes: AVX2 --------------------------------------------------------------------------
//
// Four rays, one per 64-bit lane. The lengths and end voxels are needed only by the steps that
// may end a lane; they are vectors too, blended in on a refill like the rest: kept as arrays
// written lane by lane, their 32-byte reload after each refill waited for the 8-byte stores
// (a load wider than the stores before it cannot take its data from them).
struct RayLanes {
  __m256d t0, t1, t2;  // next border crossing per axis
  __m256d d0, d1, d2;  // between two borders per axis
  __m256i index;       // bit of the current voxel
  __m256i s0, s1, s2;  // bit offset of a step per axis
  __m256d length;      // ray length
  __m256i end;         // bit of the end voxel
};

// Puts r into lane l: broadcast and blend, so the other lanes stay in registers.
KNNOCC_TARGET_AVX2 KNNOCC_ALWAYS_INLINE void put_lane(RayLanes& v, int l, const LinearRay& r) {
  const __m256i mi = _mm256_cmpeq_epi64(_mm256_set1_epi64x(l), _mm256_set_epi64x(3, 2, 1, 0));
  const __m256d m = _mm256_castsi256_pd(mi);
  v.t0 = _mm256_blendv_pd(v.t0, _mm256_set1_pd(r.state.t_max[0]), m);
  v.t1 = _mm256_blendv_pd(v.t1, _mm256_set1_pd(r.state.t_max[1]), m);
  v.t2 = _mm256_blendv_pd(v.t2, _mm256_set1_pd(r.state.t_max[2]), m);
  v.d0 = _mm256_blendv_pd(v.d0, _mm256_set1_pd(r.state.t_delta[0]), m);
  v.d1 = _mm256_blendv_pd(v.d1, _mm256_set1_pd(r.state.t_delta[1]), m);
  v.d2 = _mm256_blendv_pd(v.d2, _mm256_set1_pd(r.state.t_delta[2]), m);
  v.index = _mm256_blendv_epi8(v.index, _mm256_set1_epi64x(r.index), mi);
  v.s0 = _mm256_blendv_epi8(v.s0, _mm256_set1_epi64x(r.stride[0]), mi);
  v.s1 = _mm256_blendv_epi8(v.s1, _mm256_set1_epi64x(r.stride[1]), mi);
  v.s2 = _mm256_blendv_epi8(v.s2, _mm256_set1_epi64x(r.stride[2]), mi);
  v.length = _mm256_blendv_pd(v.length, _mm256_set1_pd(r.state.length), m);
  v.end = _mm256_blendv_epi8(v.end, _mm256_set1_epi64x(r.end_index), mi);
}

// The ray in lane l, with `steps_to_end` steps left before it can stand on its end voxel.
KNNOCC_TARGET_AVX2 inline LinearRay get_lane(const RayLanes& v, int l, std::int64_t steps_to_end) {
  alignas(32) double d[7][4];
  alignas(32) std::int64_t i[5][4];
  const __m256d dv[7] = {v.t0, v.t1, v.t2, v.d0, v.d1, v.d2, v.length};
  const __m256i iv[5] = {v.index, v.s0, v.s1, v.s2, v.end};
  for (int k = 0; k < 7; ++k) _mm256_store_pd(d[k], dv[k]);
  for (int k = 0; k < 5; ++k) _mm256_store_si256(reinterpret_cast<__m256i*>(i[k]), iv[k]);
  return LinearRay{
      {{d[0][l], d[1][l], d[2][l]}, {d[3][l], d[4][l], d[5][l]}, d[6][l], steps_to_end},
      i[0][l],
      {i[1][l], i[2][l], i[3][l]},
      i[4][l]};
}

// The axis each lane steps along next, walk_ray()'s choice in branch-free form: x if t0 < t1 and
// t0 < t2, else y if t1 < t2, else z. Advances t_max and the bit index of every lane.
KNNOCC_TARGET_AVX2 KNNOCC_ALWAYS_INLINE void advance_lanes(RayLanes& v) {
  const __m256d lt01 = _mm256_cmp_pd(v.t0, v.t1, _CMP_LT_OQ);
  const __m256d lt02 = _mm256_cmp_pd(v.t0, v.t2, _CMP_LT_OQ);
  const __m256d lt12 = _mm256_cmp_pd(v.t1, v.t2, _CMP_LT_OQ);
  const __m256d x = _mm256_and_pd(lt01, lt02);
  const __m256d y = _mm256_andnot_pd(lt01, lt12);
  const __m256d z = _mm256_or_pd(lt02, lt12);  // inverted: z steps where this is 0
  v.t0 = _mm256_add_pd(v.t0, _mm256_and_pd(x, v.d0));
  v.t1 = _mm256_add_pd(v.t1, _mm256_and_pd(y, v.d1));
  v.t2 = _mm256_add_pd(v.t2, _mm256_andnot_pd(z, v.d2));
  const __m256i stride = _mm256_blendv_epi8(_mm256_blendv_epi8(v.s2, v.s1, _mm256_castpd_si256(y)),
                                            v.s0, _mm256_castpd_si256(x));
  v.index = _mm256_add_epi64(v.index, stride);
}

// One step on the four lanes of v; returns the lanes that ended (bit l).
KNNOCC_TARGET_AVX2 KNNOCC_ALWAYS_INLINE unsigned step_lanes(RayLanes& v) {
  advance_lanes(v);
  // A lane ends on its end voxel (the bit index is one-to-one, so one comparison does what
  // walk_ray's countdown does) or once every next border lies beyond its length;
  // std::min(std::min(t0, t1), t2), operand order included (vminpd(b, a) = b < a ? b : a).
  const __m256d tmin = _mm256_min_pd(v.t2, _mm256_min_pd(v.t1, v.t0));
  const __m256d ended = _mm256_or_pd(_mm256_cmp_pd(tmin, v.length, _CMP_GT_OQ),
                                     _mm256_castsi256_pd(_mm256_cmpeq_epi64(v.index, v.end)));
  return static_cast<unsigned>(_mm256_movemask_pd(ended));
}

// One store of the four indices, then scalar shifts (as in the eight-lane walk): the indices go
// through memory, not through one transfer each from the vector unit.
template <class Marks>
KNNOCC_TARGET_AVX2 KNNOCC_ALWAYS_INLINE void mark_lanes(const RayLanes& v, Marks marks) {
  alignas(32) std::int64_t index[4];
  _mm256_store_si256(reinterpret_cast<__m256i*>(index), v.index);
  for (int l = 0; l < 4; ++l) marks(index[l]);
}

/// Four rays at once (see the top of this file). AVX2 (and BMI2 shifts), never FMA: the
/// arithmetic is walk_ray()'s, operation for operation. Most steps need no end test at all (see
/// unchecked_steps); the steps that might end a lane are taken one at a time with the test. One
/// group of four, not two: the loop is bound by its floating-point throughput, not its latency.
template <class Next, class Marks>
KNNOCC_TARGET_AVX2 std::size_t walk_linear_rays_avx2(Next& next, Marks marks) {
  constexpr int kLanes = 4;
  RayLanes v;
  v.t0 = v.t1 = v.t2 = v.d0 = v.d1 = v.d2 = v.length = _mm256_setzero_pd();
  v.index = v.s0 = v.s1 = v.s2 = v.end = _mm256_setzero_si256();
  LaneBook<kLanes> book;
  std::size_t visits = 0;
  int loaded = 0;
  for (const LinearRay* r; loaded < kLanes && (r = next()); ++loaded) {
    marks(r->index);  // the origin voxel
    ++visits;
    put_lane(v, loaded, *r);
    book.load(loaded, *r);
  }
  if (loaded < kLanes) {  // too few rays: the scalar walk
    for (int l = 0; l < loaded; ++l)
      visits += finish_linear_ray(get_lane(v, l, book.due[l]), marks);
    return visits;
  }

  for (;;) {
    // No lane can end in the next n steps: no end test.
    const std::int64_t n = book.unchecked();
    for (std::int64_t i = 0; i < n; ++i) {
      advance_lanes(v);
      mark_lanes(v, marks);
    }
    if (n > 0) {
      book.iteration += n;
      visits += static_cast<std::size_t>(n) * kLanes;
    }

    // A lane may end: one step with the end test.
    unsigned done = step_lanes(v);
    ++book.iteration;
    if (done) {
      // The lanes that ended take the next rays of the stream; a refilled lane stands on its new
      // ray's origin voxel, so the marking below covers it like the others.
      for (unsigned m = done; m; m &= m - 1) {
        const int l = __builtin_ctz(m);
        if (const LinearRay* r = next()) {
          put_lane(v, l, *r);
          book.load(l, *r);
          done &= ~(1u << l);
        } else {  // the stream ran dry: the rays still walking finish one at a time
          for (unsigned live = ~done & 0xfu; live; live &= live - 1) {
            const int j = __builtin_ctz(live);
            const LinearRay rj = get_lane(v, j, book.due[j] - book.iteration);
            marks(rj.index);
            visits += 1 + finish_linear_ray(rj, marks);
          }
          return visits;
        }
      }
    }
    mark_lanes(v, marks);
    visits += kLanes;
  }
}

#undef KNNOCC_TARGET_AVX2

#endif  // KNNOCC_AVX2_LANES

}  // namespace knnocc::detail
