// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Map quality without ground truth, for real sequences whose points carry map-point ids (ORB-SLAM
// map points): a point seen by several keyframes is almost surely real structure, so the voxels
// holding such points are a reference the map can be judged against.
//
//   MapPointViews      how many keyframes observe each map point (an id counts once per keyframe)
//                      and where it is (its first world position); seen_once() is the number of
//                      distinct map points a single keyframe observes
//   multi-view voxel   a voxel holding a map point seen by >= min_views (3) keyframes
//   evaluate_multiview(map, views, reference, options):
//     occupied            occupied voxels of the map
//     isolated            occupied voxels none of whose 26 neighbours is occupied
//     multiview           multi-view voxels
//     reference_kept      multi-view voxels occupied in the reference map (e.g. the OctoMap
//                         model's map of the same keyframes)
//     lost                of those, the ones not occupied in the map
//     free_multiview      multi-view voxels that are free (known, not occupied) in the map
//     far                 occupied voxels whose centre is farther than `far` (0.3 m) from the
//                         centre of every multi-view voxel
//
// Thread safety: const queries may run concurrently.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "../core/point3.hpp"
#include "../map/occupancy_map.hpp"

namespace knnocc::eval {

class MapPointViews {
 public:
  struct Entry {
    Point3d position;             ///< world position at the first observation
    std::uint32_t keyframes = 0;  ///< keyframes that observe the id
  };

  /// One keyframe: its points in the world frame and their ids (one per point; a repeated id
  /// counts once).
  void add_keyframe(const std::vector<Point3d>& world, const std::vector<std::uint64_t>& ids) {
    seen_.clear();
    const std::size_t n = std::min(world.size(), ids.size());
    for (std::size_t j = 0; j < n; ++j) {
      if (!seen_.insert(ids[j]).second) continue;
      auto [it, fresh] = points_.try_emplace(ids[j]);
      if (fresh) it->second.position = world[j];
      ++it->second.keyframes;
    }
    ++keyframes_;
  }

  const std::unordered_map<std::uint64_t, Entry>& points() const { return points_; }
  std::size_t size() const { return points_.size(); }
  std::size_t keyframes() const { return keyframes_; }
  /// Distinct map points that one keyframe alone observes.
  std::size_t seen_once() const { return count_at_least(1) - count_at_least(2); }
  double seen_once_fraction() const {
    return points_.empty() ? 0.0 : double(seen_once()) / double(points_.size());
  }
  /// Map points seen by at least v keyframes.
  std::size_t count_at_least(std::uint32_t v) const {
    std::size_t n = 0;
    for (const auto& e : points_) n += e.second.keyframes >= v;
    return n;
  }
  /// Median keyframes per map point (0 when empty).
  double median_views() const {
    if (points_.empty()) return 0.0;
    std::vector<std::uint32_t> v;
    v.reserve(points_.size());
    for (const auto& e : points_) v.push_back(e.second.keyframes);
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
  }

  /// The distinct voxels of `grid` holding a map point seen by >= min_views keyframes.
  template <class Key>
  std::vector<Key> multiview_voxels(const Grid<Key>& grid, std::uint32_t min_views) const {
    std::unordered_set<Key, KeyHash> keys;
    for (const auto& e : points_) {
      Key k;
      if (e.second.keyframes >= min_views && grid.point_to_key(e.second.position, k))
        keys.insert(k);
    }
    return {keys.begin(), keys.end()};
  }

 private:
  std::unordered_map<std::uint64_t, Entry> points_;
  std::unordered_set<std::uint64_t> seen_;
  std::size_t keyframes_ = 0;
};

struct MultiviewOptions {
  std::uint32_t min_views = 3;  ///< keyframes that make a map point multi-view
  double far = 0.3;             ///< "far from every multi-view voxel" (m, centre to centre)
};

struct MultiviewMetrics {
  std::size_t occupied = 0, isolated = 0, multiview = 0, reference_kept = 0, lost = 0,
              free_multiview = 0, far = 0;
};

namespace detail {
template <class T>
struct same_type {  // keeps a parameter out of template deduction (so nullptr binds)
  using type = T;
};
}  // namespace detail

/// The proxies above for `map` (`reference` may be nullptr); `reference` (may be null:
/// reference_kept and lost stay 0) is the map the lost multi-view voxels are counted against, on
/// the same grid.
template <class Key>
MultiviewMetrics evaluate_multiview(
    const OccupancyMap<Key>& map, const MapPointViews& views,
    const typename detail::same_type<OccupancyMap<Key>>::type* reference,
    MultiviewOptions opt = {}) {
  MultiviewMetrics m;
  const Grid<Key>& g = map.grid();
  const std::vector<Key> mv = views.multiview_voxels(g, opt.min_views);
  const std::unordered_set<Key, KeyHash> mv_set(mv.begin(), mv.end());
  m.multiview = mv.size();
  auto occupied_in = [](const OccupancyMap<Key>& mp, const Key& k) {
    const auto v = mp.logodds(k);
    return v && mp.is_occupied(*v);
  };
  for (const Key& k : mv) {
    const auto v = map.logodds(k);
    if (v && !map.is_occupied(*v)) ++m.free_multiview;
    if (reference && occupied_in(*reference, k)) {
      ++m.reference_kept;
      m.lost += !occupied_in(map, k);
    }
  }
  const double r = g.resolution();
  const int reach = static_cast<int>(std::ceil(opt.far / r));
  const double far2 = opt.far * opt.far;
  map.for_each_voxel([&](const Key& k, float v) {
    if (!map.is_occupied(v)) return;
    ++m.occupied;
    bool neighbour = false;
    for (int dx = -1; dx <= 1 && !neighbour; ++dx)
      for (int dy = -1; dy <= 1 && !neighbour; ++dy)
        for (int dz = -1; dz <= 1 && !neighbour; ++dz) {
          Key n;
          if ((dx || dy || dz) && shifted_key(k, dx, dy, dz, n)) neighbour = occupied_in(map, n);
        }
    m.isolated += !neighbour;
    bool near = false;
    for (int dx = -reach; dx <= reach && !near; ++dx)
      for (int dy = -reach; dy <= reach && !near; ++dy)
        for (int dz = -reach; dz <= reach && !near; ++dz) {
          Key n;
          if (double(dx * dx + dy * dy + dz * dz) * r * r > far2 * (1 + 1e-9)) continue;
          if (shifted_key(k, dx, dy, dz, n)) near = mv_set.count(n) > 0;
        }
    m.far += !near;
  });
  return m;
}

}  // namespace knnocc::eval
