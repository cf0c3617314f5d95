// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// AVX-512F code of the dense walks (x86-64, checked at run time): eight lanes of a 512-bit
// register, walk_ray()'s comparisons as mask registers (compare into a mask, add under the mask),
// the same operations on the same doubles as the four AVX2 lanes. Lanes go in two groups of eight
// that step in turn: one group's step is a chain of dependent operations, and the other group's
// step fills its latency.
//   - avx512_stream (bit marks): the two groups over a ray stream, each lane refilled as its ray
//     ends, by a countdown with no end test at all. Lanes at different points of their rays mark
//     different words.
//   - avx512_bundles (byte marks): a RayBlock sixteen neighbouring rays at a time (a bundle). A
//   lane
//     takes its ray's lane_steps, the steps no end test is needed for: a ray whose end point lies
//     clear of its voxel's borders (end_point_clear, nearly every ray) stands on its last voxel
//     before the end voxel after steps_to_end - 1 steps; any other ray takes its unchecked_steps
//     and the rest on the scalar walk. The bundle steps all sixteen lanes as far as its shortest
//     ray with no test at all, then the lanes with more steps on their own (the others frozen on a
//     voxel already marked), then takes the next sixteen: no lane is refilled while others walk.
//     With bit marks, sixteen rays in lockstep would mark the same words at once, which is why
//     bundles take bytes and the stream takes bits.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>

#include "../../core/config.hpp"
#include "../../core/detail/simd_support.hpp"
#include "linear_ray.hpp"
#include "ray_block.hpp"

namespace knnocc::detail {

#if KNNOCC_AVX2_LANES

#define KNNOCC_TARGET_AVX512 __attribute__((target("avx512f,avx2,bmi2")))
// GCC 12's AVX-512 intrinsics pass a deliberately undefined register (_mm512_undefined_*) and
// then warn about it once inlined here.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"
#endif

// Eight lanes of a 512-bit register: what both AVX-512 walks step.
namespace avx512_lanes {

constexpr int kWidth = 8;

struct Lanes {
  __m512d t0, t1, t2;  // next border crossing per axis
  __m512d d0, d1, d2;  // between two borders per axis
  __m512i index;       // the current voxel
  __m512i s0, s1, s2;  // index offset of a step per axis
};

// One step of the lanes in `active`: x if t0 < t1 and t0 < t2, else y if t1 < t2, else z.
KNNOCC_TARGET_AVX512 KNNOCC_ALWAYS_INLINE void advance(Lanes& g, __mmask8 active) {
  const __mmask8 lt01 = _mm512_cmp_pd_mask(g.t0, g.t1, _CMP_LT_OQ);
  const __mmask8 lt02 = _mm512_cmp_pd_mask(g.t0, g.t2, _CMP_LT_OQ);
  const __mmask8 lt12 = _mm512_cmp_pd_mask(g.t1, g.t2, _CMP_LT_OQ);
  const auto x = static_cast<__mmask8>(lt01 & lt02 & active);
  const auto y = static_cast<__mmask8>(~lt01 & lt12 & active);
  const auto z = static_cast<__mmask8>(~(lt02 | lt12) & active);
  g.t0 = _mm512_mask_add_pd(g.t0, x, g.t0, g.d0);
  g.t1 = _mm512_mask_add_pd(g.t1, y, g.t1, g.d1);
  g.t2 = _mm512_mask_add_pd(g.t2, z, g.t2, g.d2);
  const __m512i stride = _mm512_mask_blend_epi64(x, _mm512_mask_blend_epi64(y, g.s2, g.s1), g.s0);
  g.index = _mm512_mask_add_epi64(g.index, active, g.index, stride);
}

// The lanes' current voxels: one store of the eight indices, then scalar marks.
template <class Marks>
KNNOCC_TARGET_AVX512 KNNOCC_ALWAYS_INLINE void mark(const Lanes& g, Marks marks) {
  alignas(64) std::int64_t index[8];
  _mm512_store_si512(index, g.index);
  for (int l = 0; l < 8; ++l) marks(index[l]);
}

}  // namespace avx512_lanes

// Two groups of eight lanes over a ray stream, for bit marks: a lane ends by a countdown with no
// end test at all (a ray with a clear end stands on its end voxel after exactly steps_to_end
// steps; any other ray takes its unchecked_steps in the lane and the rest on the scalar walk) and
// takes the next ray of the stream at once; when the stream runs dry a lane is parked on a voxel
// already marked (zero strides) until every lane is done. Lanes at different points of their
// rays spread the bit marks over different words (the bundles below step sixteen neighbouring
// rays in lockstep, which with bits would mark the same words at once).
namespace avx512_stream {

using avx512_lanes::kWidth;
using avx512_lanes::mark;

/// The steps a ray takes in a lane: all of them, onto its end voxel, for a clear end; else its
/// unchecked steps (0: the scalar walk takes the whole ray).
inline std::int64_t lane_steps(const LinearRay& r) {
  return r.clear_end ? r.state.steps_to_end : unchecked_steps(r.state);
}

/// What a lane walk keeps per lane outside the vector registers: for the rays without a clear
/// end, what the scalar walk needs once the lane has taken their unchecked steps.
template <int Lanes>
struct LaneTails {
  unsigned unclear = 0;  // bit l: lane l's ray goes on on the scalar walk when its count is out
  double length[Lanes];
  std::int64_t end_index[Lanes];
  std::int64_t steps_left[Lanes];  // steps_to_end after the lane's steps

  void load(int l, const LinearRay& r, std::int64_t steps) {
    if (r.clear_end) {
      unclear &= ~(1u << l);
      return;
    }
    unclear |= 1u << l;
    length[l] = r.state.length;
    end_index[l] = r.end_index;
    steps_left[l] = r.state.steps_to_end - steps;
  }
  bool unclear_lane(int l) const { return (unclear >> l) & 1u; }
};

/// A lane's stepping state, read out of the vector registers.
struct LaneState {
  double t_max[3], t_delta[3];
  std::int64_t index, stride[3];
};

/// The ray of an unclear lane whose count ran out, ready for finish_linear_ray().
template <int Lanes>
LinearRay tail_ray(const LaneTails<Lanes>& tails, int l, const LaneState& s) {
  LinearRay r;
  for (int a = 0; a < 3; ++a) {
    r.state.t_max[a] = s.t_max[a];
    r.state.t_delta[a] = s.t_delta[a];
    r.stride[a] = s.stride[a];
  }
  r.state.length = tails.length[l];
  r.state.steps_to_end = tails.steps_left[l];
  r.index = s.index;
  r.end_index = tails.end_index[l];
  return r;
}

/// A parked lane: it stays on `voxel` (already marked) and its count never runs out.
inline LinearRay parked_ray(std::int64_t voxel) {
  LinearRay r;
  for (int a = 0; a < 3; ++a) {
    r.state.t_max[a] = std::numeric_limits<double>::infinity();
    r.state.t_delta[a] = 0.0;
    r.stride[a] = 0;
  }
  r.state.length = 0.0;
  r.state.steps_to_end = 0;
  r.index = voxel;
  r.end_index = voxel;
  return r;
}
inline constexpr std::int64_t kParkedSteps = -1;  // counts down, never reaches 0

struct Group : avx512_lanes::Lanes {
  __m512i count;  // lane steps left
};

KNNOCC_TARGET_AVX512 KNNOCC_ALWAYS_INLINE Group empty_group() {
  Group g;
  g.t0 = g.t1 = g.t2 = g.d0 = g.d1 = g.d2 = _mm512_setzero_pd();
  g.index = g.s0 = g.s1 = g.s2 = g.count = _mm512_setzero_si512();
  return g;
}

KNNOCC_TARGET_AVX512 KNNOCC_ALWAYS_INLINE void put(Group& g, int l, const LinearRay& r,
                                                   std::int64_t steps) {
  const auto m = static_cast<__mmask8>(1u << l);
  g.t0 = _mm512_mask_mov_pd(g.t0, m, _mm512_set1_pd(r.state.t_max[0]));
  g.t1 = _mm512_mask_mov_pd(g.t1, m, _mm512_set1_pd(r.state.t_max[1]));
  g.t2 = _mm512_mask_mov_pd(g.t2, m, _mm512_set1_pd(r.state.t_max[2]));
  g.d0 = _mm512_mask_mov_pd(g.d0, m, _mm512_set1_pd(r.state.t_delta[0]));
  g.d1 = _mm512_mask_mov_pd(g.d1, m, _mm512_set1_pd(r.state.t_delta[1]));
  g.d2 = _mm512_mask_mov_pd(g.d2, m, _mm512_set1_pd(r.state.t_delta[2]));
  g.index = _mm512_mask_mov_epi64(g.index, m, _mm512_set1_epi64(r.index));
  g.s0 = _mm512_mask_mov_epi64(g.s0, m, _mm512_set1_epi64(r.stride[0]));
  g.s1 = _mm512_mask_mov_epi64(g.s1, m, _mm512_set1_epi64(r.stride[1]));
  g.s2 = _mm512_mask_mov_epi64(g.s2, m, _mm512_set1_epi64(r.stride[2]));
  g.count = _mm512_mask_mov_epi64(g.count, m, _mm512_set1_epi64(steps));
}

KNNOCC_TARGET_AVX512 inline LaneState get(const Group& g, int l) {
  alignas(64) double d[6][8];
  alignas(64) std::int64_t i[4][8];
  const __m512d dv[6] = {g.t0, g.t1, g.t2, g.d0, g.d1, g.d2};
  const __m512i iv[4] = {g.index, g.s0, g.s1, g.s2};
  for (int k = 0; k < 6; ++k) _mm512_store_pd(d[k], dv[k]);
  for (int k = 0; k < 4; ++k) _mm512_store_si512(i[k], iv[k]);
  return LaneState{{d[0][l], d[1][l], d[2][l]},
                   {d[3][l], d[4][l], d[5][l]},
                   i[0][l],
                   {i[1][l], i[2][l], i[3][l]}};
}

KNNOCC_TARGET_AVX512 KNNOCC_ALWAYS_INLINE void advance(Group& g) {
  avx512_lanes::advance(g, 0xff);
  g.count = _mm512_sub_epi64(g.count, _mm512_set1_epi64(1));
}

KNNOCC_TARGET_AVX512 KNNOCC_ALWAYS_INLINE unsigned counted_out(const Group& g) {
  return _mm512_cmpeq_epi64_mask(g.count, _mm512_setzero_si512());
}

// Lane l of the two groups (g0 holds lanes 0 .. kWidth - 1).
KNNOCC_TARGET_AVX512 KNNOCC_ALWAYS_INLINE void put_lane(Group& g0, Group& g1, int l,
                                                        const LinearRay& r, std::int64_t steps) {
  if (l < kWidth)
    put(g0, l, r, steps);
  else
    put(g1, l - kWidth, r, steps);
}

// Fills lane l with the stream's next ray that has lane steps to take (rays without any go on the
// scalar walk here), its origin voxel marked and its voxels counted; false when the stream is dry.
// `marked` is then a voxel already marked.
template <class Next, class Marks>
KNNOCC_TARGET_AVX512 KNNOCC_ALWAYS_INLINE bool fill_lane(Next& next, Group& g0, Group& g1,
                                                         LaneTails<2 * kWidth>& tails, int l,
                                                         Marks marks, std::size_t& visits,
                                                         std::int64_t& marked) {
  while (const LinearRay* r = next()) {
    marks(r->index);  // the origin voxel
    marked = r->index;
    const std::int64_t steps = lane_steps(*r);
    if (steps == 0) {
      visits += 1 + finish_linear_ray(*r, marks);
      continue;
    }
    // A clear end: the origin and steps - 1 voxels before the end voxel; else the origin and the
    // lane's steps, and later what the scalar walk adds.
    visits += static_cast<std::size_t>(r->clear_end ? steps : steps + 1);
    put_lane(g0, g1, l, *r, steps);
    tails.load(l, *r, steps);
    return true;
  }
  return false;
}

/// Walks every ray next() yields in two groups of kWidth lanes, a lane refilled from the stream
/// as its ray ends (see the top of this file); returns the voxels visited.
template <class Next, class Marks>
KNNOCC_TARGET_AVX512 std::size_t walk(Next& next, Marks marks) {
  constexpr int kLanes = 2 * kWidth;
  Group g0 = empty_group(), g1 = empty_group();
  LaneTails<kLanes> tails;
  std::size_t visits = 0;
  std::int64_t marked = 0;
  unsigned live = 0;  // bit l: lane l walks a ray (else it is parked)
  for (int l = 0; l < kLanes; ++l)
    if (fill_lane(next, g0, g1, tails, l, marks, visits, marked)) live |= 1u << l;
  if (!live) return visits;
  for (int l = 0; l < kLanes; ++l)
    if (!((live >> l) & 1u)) put_lane(g0, g1, l, parked_ray(marked), kParkedSteps);

  for (;;) {
    advance(g0);
    advance(g1);
    if (const unsigned out = counted_out(g0) | counted_out(g1) << kWidth) {
      for (unsigned m = out; m; m &= m - 1) {
        const int l = __builtin_ctz(m);
        if (tails.unclear_lane(l)) {  // its unchecked steps are taken: the scalar walk goes on
          const LinearRay r = tail_ray(tails, l, l < kWidth ? get(g0, l) : get(g1, l - kWidth));
          marks(r.index);
          visits += finish_linear_ray(r, marks);
        }
        if (!fill_lane(next, g0, g1, tails, l, marks, visits, marked)) {
          put_lane(g0, g1, l, parked_ray(marked), kParkedSteps);
          live &= ~(1u << l);
        }
      }
      if (!live) return visits;
    }
    // A lane whose clear end came stands on its next ray's origin voxel now, or is parked.
    mark(g0, marks);
    mark(g1, marks);
  }
}

}  // namespace avx512_stream

// Sixteen rays at a time over a RayBlock, for byte marks (see the top of this file).
namespace avx512_bundles {

using avx512_lanes::advance;
using avx512_lanes::kWidth;
using avx512_lanes::mark;
using Group = avx512_lanes::Lanes;

// Rays i .. i + 7 of the block, on their start voxels.
KNNOCC_TARGET_AVX512 KNNOCC_ALWAYS_INLINE Group load(const RayBlock& b, std::size_t i) {
  Group g;
  g.t0 = _mm512_load_pd(b.t_max[0] + i);
  g.t1 = _mm512_load_pd(b.t_max[1] + i);
  g.t2 = _mm512_load_pd(b.t_max[2] + i);
  g.d0 = _mm512_load_pd(b.t_delta[0] + i);
  g.d1 = _mm512_load_pd(b.t_delta[1] + i);
  g.d2 = _mm512_load_pd(b.t_delta[2] + i);
  g.index = _mm512_load_si512(b.index + i);
  g.s0 = _mm512_load_si512(b.stride[0] + i);
  g.s1 = _mm512_load_si512(b.stride[1] + i);
  g.s2 = _mm512_load_si512(b.stride[2] + i);
  return g;
}

// `steps` steps of every lane of both groups, with no test. Not inlined: on its own the loop keeps
// both groups in registers (inlined into walk_block, GCC 12 spilled the marks' words to the stack).
template <class Marks>
KNNOCC_TARGET_AVX512 KNNOCC_NOINLINE void step_all(Group& g0, Group& g1, std::int64_t steps,
                                                   Marks marks) {
  Group a = g0, b = g1;
  for (std::int64_t k = 0; k < steps; ++k) {
    advance(a, 0xff);
    advance(b, 0xff);
    mark(a, marks);
    mark(b, marks);
  }
  g0 = a;
  g1 = b;
}

// The lanes' state after their lane steps, as the scalar walk takes it on.
KNNOCC_TARGET_AVX512 inline LinearRay tail_ray(const RayBlock& b, std::size_t i, const Group& g,
                                               int l) {
  alignas(64) double t[3][8];
  alignas(64) std::int64_t index[8];
  _mm512_store_pd(t[0], g.t0);
  _mm512_store_pd(t[1], g.t1);
  _mm512_store_pd(t[2], g.t2);
  _mm512_store_si512(index, g.index);
  LinearRay r = b.get(i);
  for (int a = 0; a < 3; ++a) r.state.t_max[a] = t[a][l];
  r.index = index[l];
  r.state.steps_to_end -= b.lane_steps[i];
  return r;
}

/// Walks every ray of the block, sixteen at a time (see the top of this file); returns the
/// voxels visited.
template <class Marks>
KNNOCC_TARGET_AVX512 std::size_t walk_block(const RayBlock& b, Marks marks) {
  std::size_t visits = 0;
  for (std::size_t i = 0; i < b.size; i += RayBlock::kBundle) {
    Group g0 = load(b, i), g1 = load(b, i + kWidth);
    mark(g0, marks);  // the start voxels
    mark(g1, marks);
    const __m512i c0 = _mm512_load_si512(b.lane_steps + i);
    const __m512i c1 = _mm512_load_si512(b.lane_steps + i + kWidth);
    const std::int64_t fewest = std::min(_mm512_reduce_min_epi64(c0), _mm512_reduce_min_epi64(c1));
    const std::int64_t most = std::max(_mm512_reduce_max_epi64(c0), _mm512_reduce_max_epi64(c1));
    const std::size_t rays = std::min(RayBlock::kBundle, b.size - i);
    visits += rays + static_cast<std::size_t>(_mm512_reduce_add_epi64(_mm512_add_epi64(c0, c1)));
    if (fewest > 0) step_all(g0, g1, fewest, marks);
    // The lanes with more steps to take; the others stand on a voxel they marked already.
    for (std::int64_t k = fewest; k < most; ++k) {
      const __m512i kk = _mm512_set1_epi64(k);
      advance(g0, _mm512_cmpgt_epi64_mask(c0, kk));
      advance(g1, _mm512_cmpgt_epi64_mask(c1, kk));
      mark(g0, marks);
      mark(g1, marks);
    }
    // Rays without a clear end go on on the scalar walk.
    for (std::size_t j = i; j < i + rays; ++j)
      if (!b.clear_end[j]) {
        const int l = static_cast<int>(j - i);
        visits += finish_linear_ray(
            tail_ray(b, j, l < kWidth ? g0 : g1, l < kWidth ? l : l - kWidth), marks);
      }
  }
  return visits;
}

}  // namespace avx512_bundles

#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif
#undef KNNOCC_TARGET_AVX512

#endif  // KNNOCC_AVX2_LANES

}  // namespace knnocc::detail
