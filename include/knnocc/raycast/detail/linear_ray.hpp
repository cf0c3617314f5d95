// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// LinearRay: walk_ray()'s state with a voxel index in place of a key, for walks into a dense box
// of voxels (ScanInserter's per-scan scratch). A step along axis a adds stride[a] (+-1, +-nx or
// +-nx*ny in a box of nx*ny*nz voxels) and the end voxel is an index too, so many rays can walk at
// once, one per vector lane (walk_avx2.hpp, walk_avx512.hpp). A walk marks every voxel a ray
// visits through a Marks policy: a bit per voxel (BitMarks, a read-modify-write of a 64-bit word)
// or a byte per voxel (ByteMarks, a plain store, at eight times the memory).
//
// Also here: RayEnd and RayFan (a scan's rays and what they share), end_point_clear() and
// unchecked_steps() (the proofs that let the lane walks skip end tests), and the one-ray walk.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "../../core/config.hpp"
#include "../../core/grid.hpp"
#include "../../core/point3.hpp"
#include "../dda.hpp"

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

/// Walks `r` on from its current voxel (marked already); returns the voxels visited.
template <class Marks>
std::size_t finish_linear_ray(const LinearRay& r, Marks marks) {
  IndexPosition at{r.index, r.stride, r.end_index};
  std::size_t visits = 0;
  walk_ray(r.state, at, [&](const IndexPosition& p) {
    marks(p.index);
    ++visits;
    return true;
  });
  return visits;
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

}  // namespace knnocc::detail
