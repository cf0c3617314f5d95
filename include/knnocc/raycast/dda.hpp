// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Exact 3D DDA (Amanatides & Woo) that yields exactly the keys of OctoMap's computeRayKeys:
//   - origin voxel included, end voxel never included, nothing when both share a voxel;
//   - direction, length and normalisation in float, tMax/tDelta in double, as in OctoMap;
//   - on ties the higher axis steps first (z over y over x);
//   - stops at the end key, or once the next voxel border lies beyond the ray length.
// The result is a 6-connected walk. Compile with -ffp-contract=off when FMA instructions are
// enabled (-march=native): fused multiply-adds change the last bit of borders and of the max-range
// end point, and so, rarely, a key.
//
// The walk is split in two so that several walkers share OctoMap's arithmetic: setup_walk() (via
// start_ray()) does the set-up, the one place with OctoMap's float/double rules, and walk_ray()
// the stepping, from a position (per-axis keys, or an index into a dense box) with a visitor
// that decides what entering a voxel does (a Key here, a bit or a brick mask in ScanInserter).
// raycast/detail/ holds the several-rays-at-once versions of both,
// which repeat these operations in the same order (the tests compare them bit for bit). Each
// axis moves monotonically, one voxel per step, so the walk can stand on the end voxel only after
// exactly |end - origin|_1 steps: the end test is a countdown, not a key comparison per step.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <type_traits>
#include <vector>

#include "../core/config.hpp"
#include "../core/grid.hpp"
#include "../core/point3.hpp"

namespace knnocc {

namespace detail {

/// OctoMap's Vector3::norm(): float squares summed in float, square root in double.
inline double octomap_norm(float dx, float dy, float dz) {
  const float s = dx * dx + dy * dy + dz * dz;
  return std::sqrt(static_cast<double>(s));
}

inline bool finite(const Point3f& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

/// OctoMap's max_range: > 0 a limit, < 0 none; 0 and NaN are refused (std::invalid_argument).
inline void check_max_range(double max_range) {
  if (max_range == 0.0 || std::isnan(max_range))
    invalid_argument("max_range must be > 0, or < 0 for no limit");
}

}  // namespace detail

/// End point of a ray truncated at max_range, with OctoMap's float arithmetic:
/// origin + normalized(end - origin) * float(max_range).
inline Point3f truncate_ray(const Point3f& origin, const Point3f& end, double max_range) {
  float dx = end.x - origin.x, dy = end.y - origin.y, dz = end.z - origin.z;
  const double len = detail::octomap_norm(dx, dy, dz);
  if (len > 0) {
    const float l = detail::to_float(len);  // a norm past float's range saturates to inf
    dx /= l;
    dy /= l;
    dz /= l;
  }
  const float m = detail::to_float(max_range);
  const float sx = dx * m, sy = dy * m, sz = dz * m;  // separate products: no fused multiply-add
  return Point3f{origin.x + sx, origin.y + sy, origin.z + sz};
}

/// The stepping state of a walk: per axis the ray parameter of the next border crossing and the
/// parameter between two borders, the ray length, and the steps left until the end voxel.
struct WalkState {
  double t_max[3];
  double t_delta[3];
  double length;              ///< OctoMap's float length, compared in double
  std::int64_t steps_to_end;  ///< the walk reaches the end voxel only when this hits 0
};

/// A ray ready to walk: its two voxels, the step direction per axis and the stepping state.
template <class Key>
struct RayWalk {
  Key origin, end;
  int step[3];  ///< -1, 0 (the ray never crosses this axis' borders) or +1
  WalkState state;
};

enum class RayStart {
  walk,          ///< visit `origin`, then walk_ray()
  same_voxel,    ///< origin and end share a voxel: no key at all
  out_of_range,  ///< origin or end not finite or outside the key range (computeRayKeys: false)
};

namespace detail {

/// OctoMap's computeRayKeys set-up for the segment origin -> end, given the per-axis indices of
/// their voxels (grid.point_to_key of origin and end; the two voxels differ): the step direction
/// per axis and the stepping state.
template <class Key, class Index>
void setup_walk(const Grid<Key>& grid, const Point3f& origin, const Point3f& end, const Index* ko,
                const Index* ke, int (&step)[3], WalkState& s) {
  const float o[3] = {origin.x, origin.y, origin.z};
  float dir[3] = {end.x - origin.x, end.y - origin.y, end.z - origin.z};
  const auto length = static_cast<float>(octomap_norm(dir[0], dir[1], dir[2]));
  for (float& d : dir) d /= length;

  const double res = grid.resolution();
  s.length = static_cast<double>(length);
  s.steps_to_end = 0;
  for (int i = 0; i < 3; ++i) {
    s.steps_to_end += std::llabs(static_cast<std::int64_t>(ke[i]) - ko[i]);
    step[i] = dir[i] > 0.0f ? 1 : (dir[i] < 0.0f ? -1 : 0);
    if (step[i] != 0) {
      double border = grid.index_to_coord(static_cast<typename Key::index_type>(ko[i]));
      // OctoMap's float half-voxel, static_cast<float>(step * res * 0.5), rounded once by Grid.
      border += step[i] > 0 ? grid.half_voxel_float() : -grid.half_voxel_float();
      s.t_max[i] = (border - static_cast<double>(o[i])) / static_cast<double>(dir[i]);
      s.t_delta[i] = res / static_cast<double>(std::fabs(dir[i]));
    } else {
      s.t_max[i] = std::numeric_limits<double>::max();
      s.t_delta[i] = std::numeric_limits<double>::max();
    }
  }
}

}  // namespace detail

/// OctoMap's computeRayKeys set-up for the segment origin -> end.
template <class Key>
RayStart start_ray(const Grid<Key>& grid, const Point3f& origin, const Point3f& end,
                   RayWalk<Key>& w) {
  if (!grid.point_to_key(origin, w.origin) || !grid.point_to_key(end, w.end))
    return RayStart::out_of_range;
  if (w.origin.pack() == w.end.pack()) return RayStart::same_voxel;
  detail::setup_walk(grid, origin, end, w.origin.k.data(), w.end.k.data(), w.step, w.state);
  return RayStart::walk;
}

/// Where a walk stands, per-axis voxel indices: for_each_ray_key() and ScanInserter's hashed
/// scratch walk with it (a Key is built only for a visited voxel).
struct KeyPosition {
  std::int64_t k[3];
  std::int64_t dir[3];  ///< -1, 0, +1
  std::int64_t end[3];

  template <int Axis>
  void step() {
    k[Axis] += dir[Axis];
  }
  bool at_end() const { return k[0] == end[0] && k[1] == end[1] && k[2] == end[2]; }
  /// Within [0, extent) on every axis (OctoMap only asserts this; a walk that would leave the key
  /// range ends instead).
  bool in_range(std::int64_t extent) const { return ((k[0] | k[1] | k[2]) & ~(extent - 1)) == 0; }
};

/// Where a walk stands, one index into a dense box of voxels: a step along axis a adds stride[a]
/// (the ray walks into ScanInserter's dense scratch with it, raycast/detail/).
struct IndexPosition {
  std::int64_t index;
  const std::int64_t* stride;  ///< [3], signed by the ray's step direction
  std::int64_t end;            ///< the end voxel's index

  template <int Axis>
  void step() {
    index += stride[Axis];
  }
  bool at_end() const { return index == end; }
};

/// Walks from the voxel `at` stands on (already visited) to the end of the ray. `at` is a
/// position (KeyPosition, IndexPosition, or any type with `step<Axis>()`, a move of one voxel along
/// the axis in the ray's direction, and `at_end()`, asked only when steps_to_end runs out);
/// `visit(at)` is called for every voxel the walk enters and returns false to stop (e.g. when the
/// key range is left). The next axis is the one with the smallest t_max, the higher axis on ties
/// (OctoMap's `(t0 < t1) ? (t0 < t2 ? 0 : 2) : (t1 < t2 ? 1 : 2)`); the walk ends on the end voxel
/// or when every next border lies beyond the ray length.
template <class Position, class Visit>
void walk_ray(const WalkState& s, Position& at, Visit&& visit) {
  double t0 = s.t_max[0], t1 = s.t_max[1], t2 = s.t_max[2];
  const double d0 = s.t_delta[0], d1 = s.t_delta[1], d2 = s.t_delta[2], length = s.length;
  std::int64_t steps = s.steps_to_end;
  for (;;) {
    if (t0 < t1) {
      if (t0 < t2) {
        t0 += d0;
        at.template step<0>();
      } else {
        t2 += d2;
        at.template step<2>();
      }
    } else if (t1 < t2) {
      t1 += d1;
      at.template step<1>();
    } else {
      t2 += d2;
      at.template step<2>();
    }
    if (--steps == 0 && at.at_end()) return;
    if (std::min(std::min(t0, t1), t2) > length) return;
    if (!visit(static_cast<const Position&>(at))) return;
  }
}

/// Calls visit(key) for every voxel the segment origin -> end crosses, origin voxel included,
/// end voxel excluded; a visit that returns bool stops the walk by returning false. Returns false,
/// visiting nothing, when origin or end is not finite or out of the key range (OctoMap's
/// computeRayKeys returns false there too).
template <class Key, class Visit>
bool for_each_ray_key(const Grid<Key>& grid, const Point3f& origin, const Point3f& end,
                      Visit&& visit) {
  auto go_on = [&](const Key& k) {
    if constexpr (std::is_same_v<decltype(visit(k)), bool>) {
      return visit(k);
    } else {
      visit(k);
      return true;
    }
  };
  RayWalk<Key> w;
  const RayStart start = start_ray(grid, origin, end, w);
  if (start != RayStart::walk) return start == RayStart::same_voxel;
  if (!go_on(static_cast<const Key&>(w.origin))) return true;
  KeyPosition at{{w.origin[0], w.origin[1], w.origin[2]},
                 {w.step[0], w.step[1], w.step[2]},
                 {w.end[0], w.end[1], w.end[2]}};
  walk_ray(w.state, at, [&](const KeyPosition& p) {
    if (!p.in_range(Key::extent)) return false;
    using I = typename Key::index_type;
    return go_on(Key(static_cast<I>(p.k[0]), static_cast<I>(p.k[1]), static_cast<I>(p.k[2])));
  });
  return true;
}

/// The keys of for_each_ray_key in a vector (cleared first). Returns false when out of range.
template <class Key>
bool compute_ray_keys(const Grid<Key>& grid, const Point3f& origin, const Point3f& end,
                      std::vector<Key>& out) {
  out.clear();
  return for_each_ray_key(grid, origin, end, [&](const Key& k) { out.push_back(k); });
}

}  // namespace knnocc
