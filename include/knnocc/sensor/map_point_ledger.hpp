#pragma once
// MapPointLedger: what RobustModel (sensor/robust_model.hpp) remembers per map-point id: how many
// keyframes observed the point, its first
// viewing direction, the occupied log-odds it has added to its voxel, whether it committed by the
// model's own rules (an anchor: anchors_around), and how many other keyframes' rays contradict it
// (free-space evidence against the point).
//
// A ray contradicts a map point when it crosses the point's voxel, passes within `radius` of the
// point and ends more than `margin` beyond it: the keyframe saw through where the point should
// be. Each keyframe contradicts a point at most once, and never one it observes itself. When the
// model rejects a point (enough contradictions), the evidence it added is taken back from its
// voxel (re-rating earlier evidence) and it adds nothing more.
//
// Storage: points in one vector, found by id and by voxel through open-addressing tables
// (core/detail/flat_index.hpp): the contradiction test looks up every voxel every ray crosses.
//
// Voxels are kept as packed keys (Key::pack()), so one ledger serves every key type.
//
// Thread safety: one writer (its model).

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "../core/detail/flat_index.hpp"
#include "../core/key.hpp"
#include "../core/point3.hpp"
#include "../map/occupancy_map.hpp"
#include "../raycast/dda.hpp"
#include "endpoint_rating.hpp"

namespace knnocc {

class MapPointLedger {
 public:
  struct Point {
    Point3d position;             ///< world position at the first observation
    std::uint64_t key = 0;        ///< its voxel (Key::pack())
    bool has_key = false;         ///< inside the key range
    std::uint32_t views = 0;      ///< keyframes that observed it
    std::uint32_t contra = 0;     ///< keyframes whose rays contradict it
    std::size_t first = 0;        ///< the keyframe that observed it first (created it)
    std::size_t last = 0;         ///< the latest keyframe that observed it
    std::size_t last_contra = 0;  ///< the latest keyframe that contradicted it (+1; 0: none)
    float dir[3] = {0, 0, 0};     ///< first viewing direction (unit)
    float added = 0.0f;           ///< occupied log-odds it added to its voxel so far
    bool rejected = false;        ///< its evidence was taken back
    bool anchor = false;          ///< committed by the model's own rules (PointContext::anchor)
  };

  /// The point `id` observed by `keyframe` at `p` from `origin` (its first position is kept);
  /// returns it with views counted once per keyframe.
  template <class Key>
  Point& observe(std::uint64_t id, const Point3d& p, const Point3d& origin, std::size_t keyframe,
                 const Grid<Key>& grid) {
    bool fresh = false;
    const std::uint32_t i =
        index_.find_or_insert(id, static_cast<std::uint32_t>(points_.size()), fresh);
    if (fresh) {
      points_.emplace_back();
      ids_.push_back(id);
    }
    Point& e = points_[i];
    if (fresh) {
      e.position = p;
      e.first = keyframe;
      const double dx = p.x - origin.x, dy = p.y - origin.y, dz = p.z - origin.z;
      const double r = std::sqrt(dx * dx + dy * dy + dz * dz);
      if (r > 0) {
        e.dir[0] = static_cast<float>(dx / r);
        e.dir[1] = static_cast<float>(dy / r);
        e.dir[2] = static_cast<float>(dz / r);
      }
      Key k;
      e.has_key = grid.point_to_key(p, k);
      if (e.has_key) {
        e.key = k.pack();
        bool new_cell = false;
        const std::uint32_t c =
            cells_.find_or_insert(e.key, static_cast<std::uint32_t>(cell_points_.size()), new_cell);
        if (new_cell) cell_points_.emplace_back();
        cell_points_[c].push_back(i);
      }
    }
    if (fresh || e.last != keyframe) {
      ++e.views;
      e.last = keyframe;
    }
    return e;
  }

  /// Angle (rad) between the point's first viewing direction and the ray origin -> p.
  static double parallax(const Point& e, const Point3d& p, const Point3d& origin) {
    const double dx = p.x - origin.x, dy = p.y - origin.y, dz = p.z - origin.z;
    const double r = std::sqrt(dx * dx + dy * dy + dz * dz);
    if (!(r > 0)) return 0.0;
    const double c = (e.dir[0] * dx + e.dir[1] * dy + e.dir[2] * dz) / r;
    return std::acos(c > 1.0 ? 1.0 : c < -1.0 ? -1.0 : c);
  }

  /// Counts the contradictions the rays of keyframe `keyframe` (origin -> world[j] for each j
  /// with ratings[j].casts_ray) bring, then calls rejects(views, contradictions) for each point
  /// they touched and takes back the evidence of the newly rejected ones from `map`. Returns the
  /// number of points rejected.
  template <class Key, class Rejects>
  std::size_t contradict(const Point3d& origin, const std::vector<Point3d>& world,
                         const std::vector<EndpointRating>& ratings, std::size_t keyframe,
                         double radius, double margin, OccupancyMap<Key>& map, Rejects&& rejects) {
    if (points_.empty()) return 0;
    touched_.clear();
    const Point3f o = detail::to_point3f(origin);
    const double r2 = radius * radius;
    for (std::size_t j = 0; j < world.size(); ++j) {
      if (!ratings[j].casts_ray) continue;
      const Point3d& e = world[j];
      const double ux = e.x - origin.x, uy = e.y - origin.y, uz = e.z - origin.z;
      const double len = std::sqrt(ux * ux + uy * uy + uz * uz);
      if (!(len > margin)) continue;
      const double f = (len - margin) / len;
      const Point3f stop =
          detail::to_point3f(Point3d{origin.x + ux * f, origin.y + uy * f, origin.z + uz * f});
      for_each_ray_key(map.grid(), o, stop, [&](const Key& k) {
        const std::uint32_t cell = cells_.find(k.pack());
        if (cell == detail::FlatIndex::kNone) return;
        for (const std::uint32_t id : cell_points_[cell]) {
          Point& p = points_[id];
          if (p.last == keyframe || p.last_contra == keyframe + 1 || p.rejected) continue;
          const double px = p.position.x - origin.x, py = p.position.y - origin.y,
                       pz = p.position.z - origin.z;
          const double t = (px * ux + py * uy + pz * uz) / len;
          if (!(t > 0 && t < len - margin)) continue;
          if (px * px + py * py + pz * pz - t * t > r2) continue;
          ++p.contra;
          p.last_contra = keyframe + 1;
          touched_.push_back(id);
        }
      });
    }
    std::size_t rejected = 0;
    for (const std::uint32_t id : touched_) {
      Point& p = points_[id];
      if (p.rejected || !rejects(p.views, p.contra)) continue;
      p.rejected = true;
      ++rejected;
      if (p.has_key && p.added != 0.0f) map.update(Key::unpack(p.key), -p.added);
      p.added = 0.0f;
    }
    return rejected;
  }

  /// Calls f(id, point) for every point whose first position lies in `key`'s voxel or one of
  /// the 26 around it.
  template <class Key, class F>
  void for_each_around(const Key& key, F&& f) {
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          Key n;
          if (!shifted_key(key, dx, dy, dz, n)) continue;
          const std::uint32_t cell = cells_.find(n.pack());
          if (cell == detail::FlatIndex::kNone) continue;
          for (const std::uint32_t i : cell_points_[cell]) f(ids_[i], points_[i]);
        }
  }

  /// Anchors (points with `anchor`, not rejected) whose first position lies in `key`'s voxel or
  /// one of the 26 around it.
  template <class Key>
  std::uint32_t anchors_around(const Key& key) {
    std::uint32_t n = 0;
    for_each_around(key, [&](std::uint64_t, const Point& p) { n += p.anchor && !p.rejected; });
    return n;
  }

  const Point* find(std::uint64_t id) const {
    const std::uint32_t i = index_.find(id);
    return i == detail::FlatIndex::kNone ? nullptr : &points_[i];
  }
  Point* find(std::uint64_t id) {
    const std::uint32_t i = index_.find(id);
    return i == detail::FlatIndex::kNone ? nullptr : &points_[i];
  }
  std::size_t size() const { return points_.size(); }
  /// Calls f(id, point) for every map point, in the order of their first observation.
  template <class F>
  void for_each(F&& f) const {
    for (std::size_t i = 0; i < points_.size(); ++i) f(ids_[i], points_[i]);
  }

 private:
  std::vector<Point> points_;
  std::vector<std::uint64_t> ids_;
  detail::FlatIndex index_;  // id -> index in points_ (ids are never 2^64-1: KeyframeUnion::kNoId)
  detail::FlatIndex cells_;  // packed voxel key -> index in cell_points_
  std::vector<std::vector<std::uint32_t>> cell_points_;
  std::vector<std::uint32_t> touched_;
};

}  // namespace knnocc
