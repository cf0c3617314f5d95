#pragma once
// Walking rays into a dense per-scan scratch: ScanInserter's hot loop.
//
// A LinearRay is walk_ray()'s state (raycast/dda.hpp) with a voxel index in place of a key: a
// step along axis a adds stride[a] (+-1, +-nx or +-nx*ny in a box of nx*ny*nz voxels), and the
// end voxel is an index too. A walk marks every voxel a ray visits, through a Marks policy: one
// bit per voxel (BitMarks, a read-modify-write of a 64-bit word) or one byte per voxel
// (ByteMarks, a plain store). Bytes are what the lanes below mark fastest: rays from one origin
// cross the same few voxels near it, and bit marks of neighbouring voxels then wait on each
// other's stores to the same word (TUM's rays at 0.05 m: the walk alone took about half the
// time with bytes), at eight times the memory, so ScanInserter takes bytes for small boxes only.
//
// The scalar walk spends most of its time on one branch: which axis steps next, a coin flip for
// the CPU's predictor. On x86-64 CPUs with AVX2 (checked at run time) rays walk several at once,
// one per 64-bit lane, with walk_ray()'s comparisons in branch-free form: the same comparisons on
// the same doubles, so exactly the same voxels.
//   - AVX-512F with byte marks: a RayBlock (up to 256 rays set up field by field) walks sixteen
//     rays at a time, a bundle, in two groups of eight lanes that step in turn (one group's chain
//     of dependent compare, mask and add operations fills the other's latency). A lane takes its
//     ray's lane_steps, the steps no end test is needed for: a ray whose end point lies clear of
//     its voxel's borders (end_point_clear, nearly every ray) stands on its last voxel before the
//     end voxel after steps_to_end - 1 steps; any other ray takes its unchecked_steps and the rest
//     on the scalar walk. The bundle steps all sixteen lanes as far as its shortest ray with no
//     test at all, then the lanes with more steps on their own (the others frozen on a voxel
//     already marked), then takes the next sixteen: no lane is refilled while others walk.
//   - AVX-512F with bit marks: two groups of eight lanes over a ray stream, each lane refilled as
//     its ray ends, by a countdown with no end test (avx512_stream below).
//   - AVX2: four lanes over a ray stream. They test for ends only in the steps where a lane can
//     end: the last one for a ray with a clear end, the last four otherwise. A lane whose ray ends
//     takes the next ray of the stream; when the stream runs dry the remaining rays finish on the
//     scalar walk. KNNOCC_NO_AVX512 keeps AVX-512 CPUs on the four lanes.
// The set-up of the rays (setup_walk) goes eight at a time on AVX2 CPUs. Precondition of the
// vector paths: a box of fewer than 2^16 + 64 voxels per edge (ScanInserter's kDenseMaxEdge),
// which bounds both a ray's rounding error (unchecked_steps) and the voxel indices converted
// through doubles in the set-up. Elsewhere (no AVX2, other architectures, or KNNOCC_NO_SIMD
// defined) everything runs on the scalar code, with the same results.
//
// Ray streams (the four-lane and scalar walks): next() returns a pointer to the next ray (valid
// until the following call), or nullptr when there are no more.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <memory>
#include <type_traits>

#include "../core/config.hpp"
#include "../raycast/dda.hpp"

#include "simd_support.hpp"

namespace knnocc::detail {

/// One ray of a dense scratch, ready to walk from its current voxel `index`.
struct LinearRay {
  WalkState state;
  std::int64_t index;      ///< bit of the voxel the walk stands on
  std::int64_t stride[3];  ///< bit offset of one step along each axis (0: never steps)
  std::int64_t end_index;  ///< bit of the end voxel
  bool clear_end = false;  ///< the walk cannot end before steps_to_end (see end_point_clear)
};

/// A ray of a scan, as ScanInserter collects it: its end point and end voxel (different from the
/// origin's; the origin is the scan's).
struct RayEnd {
  Point3f end;
  std::int32_t key[3];
};

/// What all rays of a scan share when they are set up as LinearRays: the origin, its voxel and
/// borders, and the dense box (bit index = sum over axes of (key - lo) * stride).
struct RayFan {
  Point3f origin;
  std::int32_t origin_key[3];
  double resolution;
  double inv_resolution;  // 1 / resolution, as KeyRounding
  double border[3][2];    // [axis][step > 0]: setup_walk's border of the origin voxel
  std::int64_t lo[3], stride[3];

  template <class Key>
  RayFan(const Grid<Key>& grid, const Point3f& o, const std::int32_t (&ko)[3],
         const std::int64_t (&box_lo)[3], const std::int64_t (&box_stride)[3])
      : origin(o), resolution(grid.resolution()), inv_resolution(1.0 / grid.resolution()) {
    for (int a = 0; a < 3; ++a) {
      origin_key[a] = ko[a];
      lo[a] = box_lo[a];
      stride[a] = box_stride[a];
      for (const int step : {-1, 1}) {  // exactly setup_walk's two statements
        double b = grid.index_to_coord(static_cast<typename Key::index_type>(ko[a]));
        b += step > 0 ? grid.half_voxel_float() : -grid.half_voxel_float();
        border[a][step > 0] = b;
      }
    }
  }
  std::int64_t index(const std::int32_t (&k)[3]) const {
    return (k[0] - lo[0]) * stride[0] + (k[1] - lo[1]) * stride[1] + (k[2] - lo[2]) * stride[2];
  }
};

/// Margin, in voxels, that end_point_clear() asks between an end point and its voxel's borders.
inline double end_margin(double length_voxels) { return 1e-5 * length_voxels + 1e-3; }

/// Whether the walk of `ray` (of float length `length`) provably ends on its end voxel after
/// exactly steps_to_end steps, never earlier by its length: true when along every axis the end
/// point lies more than end_margin() voxels inside its voxel. Why that suffices: along each axis
/// the walk crosses a border where origin + t * (float direction) meets it, and at t = length
/// that line is within 5e-7 * length of the end point (a loose bound: the float differences,
/// norm and division each err by under 2^-24 relative; the norm's error largely cancels). The
/// rest errs by far less: the float half-voxel of the first border (1.5e-8 voxel), the double
/// sums of t_delta, and the key rounding. So at t = length the walk has crossed, along each axis,
/// exactly the borders between the origin's voxel and the end voxel and no other: steps_to_end
/// crossings lie below the length, and after any earlier step the next crossing, which the
/// length test compares, is one of them, so no step before steps_to_end ends the walk. The margin
/// is 20 times that loose bound, plus 1e-3 voxel. After steps_to_end steps, then, the walk has
/// crossed exactly those borders and stands on the end voxel, which ends it: the lane walks end a
/// flagged ray by its step count alone. A test walks rays 0-40 float steps from borders and checks
/// the claim on every ray it flags.
template <class Key>
bool end_point_clear(const RayFan& fan, const RayEnd& ray, double length) {
  const double margin = end_margin(length * fan.inv_resolution);
  const float e[3] = {ray.end.x, ray.end.y, ray.end.z};
  bool clear = true;
  for (int a = 0; a < 3; ++a) {
    // The end point's place in its voxel: KeyRounding's scaled coordinate less the voxel's index.
    const double f = fan.inv_resolution * static_cast<double>(e[a]) -
                     static_cast<double>(ray.key[a] - static_cast<std::int32_t>(Key::center));
    clear = clear && f > margin && f < 1.0 - margin;
  }
  return clear;
}

/// One ray's set-up: setup_walk() (OctoMap's arithmetic) and the bit indices.
template <class Key>
void setup_linear_ray(const Grid<Key>& grid, const RayFan& fan, const RayEnd& ray, LinearRay& r) {
  int step[3];
  setup_walk(grid, fan.origin, ray.end, fan.origin_key, ray.key, step, r.state);
  r.index = fan.index(fan.origin_key);
  r.end_index = fan.index(ray.key);
  for (int a = 0; a < 3; ++a) r.stride[a] = step[a] * fan.stride[a];
  r.clear_end = end_point_clear<Key>(fan, ray, r.state.length);
}

KNNOCC_ALWAYS_INLINE void set_bit(std::uint64_t* bits, std::int64_t i) {
  bits[i >> 6] |= std::uint64_t{1} << (i & 63);
}

/// Marks one bit per voxel: bit i & 63 of word i >> 6 (ScanBitmap).
struct BitMarks {
  std::uint64_t* words;
  KNNOCC_ALWAYS_INLINE void operator()(std::int64_t i) const { set_bit(words, i); }
};

/// Marks one byte per voxel: byte i becomes 1 (a ScanBitmap with a byte per voxel).
struct ByteMarks {
  std::uint8_t* bytes;
  KNNOCC_ALWAYS_INLINE void operator()(std::int64_t i) const { bytes[i] = 1; }
};

// walk_ray()'s cursor for voxel indices.
template <class Marks>
struct MarkCursor {
  std::int64_t index;
  const std::int64_t* stride;
  std::int64_t end_index;
  Marks marks;
  std::size_t visits = 0;

  template <int Axis>
  void step() {
    index += stride[Axis];
  }
  bool at_end() const { return index == end_index; }
  bool visit() {
    marks(index);
    ++visits;
    return true;
  }
};

/// Walks `r` on from its current voxel (marked already); returns the voxels visited.
template <class Marks>
std::size_t finish_linear_ray(const LinearRay& r, Marks marks) {
  MarkCursor<Marks> cursor{r.index, r.stride, r.end_index, marks};
  walk_ray(r.state, cursor);
  return cursor.visits;
}

/// Steps a walk takes before it can end, counted from its start: none of them needs walk_ray()'s
/// end tests. A walk stands on its end voxel only after exactly steps_to_end steps (one voxel per
/// step, each axis monotonic). It ends by its length once every next border lies beyond the
/// length, which along an axis where the end voxel lies two or more borders ahead would take an
/// error of a whole voxel in the float direction and length (they err by under 0.2 voxel for the
/// rays of a dense box, whose edges stay below 2^16 + 64 voxels): so only with every axis at most
/// one voxel short of the end voxel, i.e. within the last three steps before steps_to_end.
inline std::int64_t unchecked_steps(std::int64_t steps_to_end) {
  return steps_to_end > 4 ? steps_to_end - 4 : 0;
}
inline std::int64_t unchecked_steps(const WalkState& s) { return unchecked_steps(s.steps_to_end); }

/// The one-ray-at-a-time walk.
template <class Next, class Marks>
std::size_t walk_linear_rays_scalar(Next& next, Marks marks) {
  std::size_t visits = 0;
  while (const LinearRay* r = next()) {
    marks(r->index);  // the origin voxel
    visits += 1 + finish_linear_ray(*r, marks);
  }
  return visits;
}

/// Up to kRays rays set up for the walks, field by field (a structure of arrays, so that the
/// AVX-512 walk loads one field of eight rays in one instruction). Entries from size up to the
/// next multiple of kBundle are parked rays: they stand on the first ray's start voxel and never
/// step.
struct RayBlock {
  static constexpr std::size_t kRays = 256;
  static constexpr std::size_t kBundle = 16;  // rays the AVX-512 walk takes at once

  alignas(64) double t_max[3][kRays];
  alignas(64) double t_delta[3][kRays];
  alignas(64) std::int64_t stride[3][kRays];
  alignas(64) std::int64_t index[kRays];       // start voxel
  alignas(64) std::int64_t lane_steps[kRays];  // steps with no end test (lane_steps_of)
  double length[kRays];
  std::int64_t end_index[kRays];
  std::int64_t steps_to_end[kRays];
  bool clear_end[kRays];
  std::size_t size = 0;

  /// The steps a ray takes before any end test: for a clear end, all but the step onto the end
  /// voxel (so the ray's voxels are walked, and nothing more); else its unchecked steps, and the
  /// scalar walk goes on from there.
  static std::int64_t lane_steps_of(std::int64_t steps_to_end, bool clear_end) {
    return clear_end ? steps_to_end - 1 : unchecked_steps(steps_to_end);
  }

  void set(std::size_t i, const LinearRay& r) {
    for (int a = 0; a < 3; ++a) {
      t_max[a][i] = r.state.t_max[a];
      t_delta[a][i] = r.state.t_delta[a];
      stride[a][i] = r.stride[a];
    }
    index[i] = r.index;
    length[i] = r.state.length;
    end_index[i] = r.end_index;
    steps_to_end[i] = r.state.steps_to_end;
    clear_end[i] = r.clear_end;
    lane_steps[i] = lane_steps_of(r.state.steps_to_end, r.clear_end);
  }
  LinearRay get(std::size_t i) const {
    LinearRay r;
    for (int a = 0; a < 3; ++a) {
      r.state.t_max[a] = t_max[a][i];
      r.state.t_delta[a] = t_delta[a][i];
      r.stride[a] = stride[a][i];
    }
    r.index = index[i];
    r.state.length = length[i];
    r.end_index = end_index[i];
    r.state.steps_to_end = steps_to_end[i];
    r.clear_end = clear_end[i];
    return r;
  }
  /// Sets size = n (1 <= n <= kRays, rays 0 .. n - 1 set) and parks the rest of the last bundle.
  void close(std::size_t n) {
    size = n;
    for (std::size_t i = n; i % kBundle != 0; ++i) {
      for (int a = 0; a < 3; ++a) {
        t_max[a][i] = std::numeric_limits<double>::infinity();
        t_delta[a][i] = 0.0;
        stride[a][i] = 0;
      }
      index[i] = end_index[i] = index[0];
      length[i] = 0.0;
      steps_to_end[i] = lane_steps[i] = 0;
      clear_end[i] = true;
    }
  }
};

/// A RayBlock's rays as a ray stream (for the four-lane and scalar walks).
class BlockRays {
 public:
  explicit BlockRays(const RayBlock& block) : block_(block) {}
  const LinearRay* operator()() {
    if (next_ == block_.size) return nullptr;
    ray_ = block_.get(next_++);
    return &ray_;
  }

 private:
  const RayBlock& block_;
  std::size_t next_ = 0;
  LinearRay ray_;
};

// What the four-lane walk keeps per lane outside the vector registers.
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
  // (Adding to every lane and blending was measured too: 3% slower here.)
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
// through memory, not through one transfer each from the vector unit (0.94-0.95 of the time in two
// of three interleaved runs of TUM's rays on an AMD EPYC with AVX2, 1.03 in the third).
template <class Marks>
KNNOCC_TARGET_AVX2 KNNOCC_ALWAYS_INLINE void mark_lanes(const RayLanes& v, Marks marks) {
  alignas(32) std::int64_t index[4];
  _mm256_store_si256(reinterpret_cast<__m256i*>(index), v.index);
  for (int l = 0; l < 4; ++l) marks(index[l]);
}

/// Four rays at once (see the top of this file). AVX2 (and BMI2 shifts), never FMA: the
/// arithmetic is walk_ray()'s, operation for operation. Most steps need no end test at all (see
/// unchecked_steps); the steps that might end a lane are taken one at a time with the test.
/// (Eight rays in two groups of four were measured too: slower, the loop is bound by its
/// floating-point throughput, not its latency.)
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

// ---- two groups of eight lanes: AVX-512 --------------------------------------------------------
//
// walk_ray()'s comparisons as mask registers (compare into a mask, add under the mask): the same
// operations on the same doubles as the four lanes. Measured on an AMD EPYC (Zen 5): one group of
// eight stepping alone waits on its own chain, 5.1 ns a step against 2.2 ns per group with two
// groups in turn. Two groups of four lanes did not gain on the four-lane walk above: their 22
// vectors do not fit AVX2's 16 registers. TUM's rays at 0.05 m (62 M visits, the walk alone in a
// throw-away harness): about 51 ms with bit marks, either way below; 26 ms as bundles with byte
// marks, against 46 ms for the stream walk with byte marks.

#define KNNOCC_TARGET_AVX512 __attribute__((target("avx512f,avx2,bmi2")))
// GCC 12's AVX-512 intrinsics pass a deliberately undefined register (_mm512_undefined_*) and
// then warn about it once inlined here.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"
#endif

inline bool cpu_has_avx512() {
#if defined(__AVX512F__) && defined(__BMI2__)
  return true;
#else
  static const bool has = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("bmi2");
  return has;
#endif
}

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
// rays spread the bit marks over different words: the bundles below, whose sixteen neighbouring
// rays step in lockstep, marked the same words at once and took 1.2 times as long with bits.
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
/// as its ray ends (see the top of ray_lanes.hpp); returns the voxels visited.
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

// Sixteen rays at a time over a RayBlock, for byte marks (see the top of ray_lanes.hpp).
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

/// Walks every ray of the block, sixteen at a time (see the top of ray_lanes.hpp); returns the
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

/// Walks every ray next() yields (two groups of eight lanes on AVX-512 CPUs, four lanes on AVX2
/// CPUs, else one at a time), marking each voxel visited (origin included, end excluded, exactly
/// walk_ray()'s voxels). Returns the number of voxels visited.
template <class Next, class Marks>
std::size_t walk_linear_rays(Next& next, Marks marks) {
#if KNNOCC_AVX2_LANES
#if !defined(KNNOCC_NO_AVX512)
  if (cpu_has_avx512()) return avx512_stream::walk(next, marks);
#endif
  if (cpu_has_avx2()) return walk_linear_rays_avx2(next, marks);
#endif
  return walk_linear_rays_scalar(next, marks);
}

/// Whether walk_ray_block() takes sixteen rays at a time: on AVX-512 CPUs with byte marks. Else a
/// block's rays are best walked as part of a longer stream (walk_linear_rays), whose lanes do not
/// wait for each other.
template <class Marks>
bool walks_bundles() {
#if KNNOCC_AVX2_LANES && !defined(KNNOCC_NO_AVX512)
  return std::is_same_v<Marks, ByteMarks> && cpu_has_avx512();
#else
  return false;
#endif
}

/// Walks every ray of the block: sixteen at a time where walks_bundles(), else as a ray stream.
/// Marks and returns as walk_linear_rays.
template <class Marks>
std::size_t walk_ray_block(const RayBlock& block, Marks marks) {
#if KNNOCC_AVX2_LANES && !defined(KNNOCC_NO_AVX512)
  if (walks_bundles<Marks>()) return avx512_bundles::walk_block(block, marks);
#endif
  BlockRays rays(block);
  return walk_linear_rays(rays, marks);
}

/// setup_linear_ray() for rays[0..n) (1 <= n <= RayBlock::kRays) into `block`, eight at a time
/// on AVX2 machines; closes the block (RayBlock::close). Never inlined: the AVX-512 walk's target
/// enables FMA, and contracting OctoMap's float arithmetic inside it (-ffp-contract=fast, GCC's
/// default for gnu++17, or clang's default "on") would change bits; compiled on its own it keeps
/// the caller's flags.
template <class Key>
KNNOCC_NOINLINE void setup_ray_block(const Grid<Key>& grid, const RayFan& fan, const RayEnd* rays,
                                     std::size_t n, RayBlock& block) {
  std::size_t i = 0;
#if KNNOCC_AVX2_LANES
  if (cpu_has_avx2())
    for (; i + 8 <= n; i += 8) setup_linear_rays8<Key>(fan, rays + i, block, i);
#endif
  for (; i < n; ++i) {
    LinearRay r;
    setup_linear_ray(grid, fan, rays[i], r);
    block.set(i, r);
  }
  block.close(n);
}

/// setup_ray_block() for any number of rays, into LinearRays (tests and benchmarks).
template <class Key>
void setup_linear_rays(const Grid<Key>& grid, const RayFan& fan, const RayEnd* rays, std::size_t n,
                       LinearRay* out) {
  const auto block = std::make_unique<RayBlock>();
  for (std::size_t first = 0; first < n; first += RayBlock::kRays) {
    const std::size_t count = std::min(RayBlock::kRays, n - first);
    setup_ray_block(grid, fan, rays + first, count, *block);
    for (std::size_t i = 0; i < count; ++i) out[first + i] = block->get(i);
  }
}

}  // namespace knnocc::detail
