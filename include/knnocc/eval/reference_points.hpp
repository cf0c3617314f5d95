// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A reference given as points, e.g. the vertices of a room model (../shared/data/
// icl_living_room_traj2n/reference.ply): voxelised for the authors' counting
// (eval/confusion.hpp), and precision and recall by distance to the points.
//
//   PointVoxels        a cell holding a reference point is occupied; the other cells of the points'
//                      bounding box grown by `margin` voxels are free; outside it, unknown
//   point_coverage(map, ref, seen):
//     occupied         occupied cells of the map
//     near             of those, the ones within one voxel of a reference point (a reference cell
//                      among the cell and its 26 neighbours)          precision = near / occupied
//     visible          reference cells within one voxel of a `seen` cell (a cell holding a point
//                      the sequence observed); all reference cells without `seen`
//     covered          of those, the ones within one voxel of an occupied map cell
//                                                                     recall = covered / visible
// A model given by its vertices only has, on a large flat face, points at the corners alone: the
// distance to the nearest vertex is an upper bound of the distance to the surface. So precision
// here is a lower bound (a wall voxel far from every corner counts as not near), recall weighs
// detailed parts (many vertices) more than flat ones, and PointVoxels calls the inside of flat
// faces free: FP and FN of the counting against it are upper bounds too.
//
// Thread safety: const functions of const objects; may run concurrently.

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <unordered_set>
#include <vector>

#include "../core/grid.hpp"
#include "../core/key.hpp"
#include "../map/occupancy_map.hpp"
#include "confusion.hpp"

namespace knnocc::eval {

template <class Key>
class PointVoxels {
 public:
  using KeySet = std::unordered_set<Key, KeyHash>;

  /// The cells of `points` (any point type) on `grid`; points outside the key range are left
  /// out. margin: free cells around the points' bounding box (voxels).
  template <class Points>
  PointVoxels(const Points& points, const Grid<Key>& grid, int margin = 1) : grid_(grid) {
    for (const auto& p : points) {
      Key k;
      if (!grid.point_to_key(p, k)) continue;
      cells_.insert(k);
      for (int a = 0; a < 3; ++a) {
        lo_[a] = std::min<std::int64_t>(lo_[a], k[a]);
        hi_[a] = std::max<std::int64_t>(hi_[a], k[a]);
      }
    }
    for (int a = 0; a < 3; ++a) {
      lo_[a] -= margin;
      hi_[a] += margin;
    }
  }

  bool known(const Key& k) const {
    for (int a = 0; a < 3; ++a)
      if (k[a] < lo_[a] || k[a] > hi_[a]) return false;
    return true;
  }
  bool occupied(const Key& k) const { return cells_.count(k) > 0; }
  const KeySet& cells() const { return cells_; }
  const Grid<Key>& grid() const { return grid_; }

 private:
  Grid<Key> grid_;
  KeySet cells_;
  static constexpr std::int64_t kMax = std::numeric_limits<std::int64_t>::max();
  std::array<std::int64_t, 3> lo_{kMax, kMax, kMax}, hi_{-kMax, -kMax, -kMax};
};

struct PointCoverage {
  std::size_t occupied = 0, near = 0, visible = 0, covered = 0;
  double precision() const { return occupied ? double(near) / double(occupied) : 0.0; }
  double recall() const { return visible ? double(covered) / double(visible) : 0.0; }
};

namespace detail {
template <class Key, class Set>
bool any_within_one(const Key& k, const Set& set) {
  for (const auto& d : tolerance_offsets()) {
    Key n;
    if (shifted_key(k, d[0], d[1], d[2], n) && set.count(n)) return true;
  }
  return false;
}
}  // namespace detail

/// Precision and recall of `map` against the reference points (see above); `seen` (may be null:
/// every reference cell is visible) the cells holding the points the sequence observed, on the
/// map's grid. `threshold` as in ConfusionOptions.
template <class Key>
PointCoverage point_coverage(const OccupancyMap<Key>& map, const PointVoxels<Key>& ref,
                             const typename PointVoxels<Key>::KeySet* seen,
                             const ConfusionOptions& opt = {}) {
  PointCoverage c;
  std::unordered_set<Key, KeyHash> occupied;
  map.for_each_voxel([&](const Key& k, float v) {
    if (opt.threshold ? v >= *opt.threshold : map.is_occupied(v)) occupied.insert(k);
  });
  c.occupied = occupied.size();
  for (const Key& k : occupied) c.near += detail::any_within_one(k, ref.cells());
  for (const Key& k : ref.cells()) {
    if (seen && !detail::any_within_one(k, *seen)) continue;
    ++c.visible;
    c.covered += detail::any_within_one(k, occupied);
  }
  return c;
}

}  // namespace knnocc::eval
