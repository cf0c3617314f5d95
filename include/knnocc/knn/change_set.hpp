// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// ChangeSet: how the map point cloud changed between two keyframes (paper section 3.2): new
// points (added), disappeared points (removed) and points whose position changed (moved, e.g.
// after bundle adjustment). The affected points follow from these (knn/tracker.hpp).
//
// Builders:
//   - diff_by_id(previous, next): two successive map clouds with ids (what ORB-SLAM gives);
//   - SpatialChangeDetector: clouds without ids, compared voxel by voxel at a resolution, like
//     PCL's octree change detection used in the paper (a voxel that becomes occupied brings its
//     points in as new, a voxel that empties takes its points out; voxels occupied in both keep
//     the points they had).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "../core/config.hpp"
#include "../core/point3.hpp"
#include "../core/point_traits.hpp"

namespace knnocc {

struct IdPoint {
  std::uint64_t id = 0;
  Point3d p;
};

struct ChangeSet {
  std::vector<IdPoint> added;
  std::vector<std::uint64_t> removed;
  std::vector<IdPoint> moved;  ///< id keeps its identity, position is the new one

  bool empty() const { return added.empty() && removed.empty() && moved.empty(); }
  std::size_t size() const { return added.size() + removed.size() + moved.size(); }
};

template <class P>
Point3d to_point3d(const P& p) {
  return Point3d{static_cast<double>(point_x(p)), static_cast<double>(point_y(p)),
                 static_cast<double>(point_z(p))};
}

/// Change from `previous` to `next`, both maps id -> position. A position counts as moved when
/// any coordinate differs by more than `tolerance` (0: any difference).
inline bool is_finite(const Point3d& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

/// Entries with a NaN/Inf coordinate count as absent (the tracker never holds such points).
inline ChangeSet diff_by_id(const std::unordered_map<std::uint64_t, Point3d>& previous,
                            const std::unordered_map<std::uint64_t, Point3d>& next,
                            double tolerance = 0.0) {
  ChangeSet cs;
  for (const auto& [id, p] : next) {
    if (!is_finite(p)) continue;
    auto it = previous.find(id);
    if (it == previous.end() || !is_finite(it->second)) {
      cs.added.push_back({id, p});
      continue;
    }
    const Point3d& q = it->second;
    if (std::fabs(p.x - q.x) > tolerance || std::fabs(p.y - q.y) > tolerance ||
        std::fabs(p.z - q.z) > tolerance)
      cs.moved.push_back({id, p});
  }
  for (const auto& [id, p] : previous) {
    if (!is_finite(p)) continue;
    auto it = next.find(id);
    if (it == next.end() || !is_finite(it->second)) cs.removed.push_back(id);
  }
  // Hash order is not deterministic across libraries; sorted lists make runs reproducible.
  auto by_id = [](const IdPoint& a, const IdPoint& b) { return a.id < b.id; };
  std::sort(cs.added.begin(), cs.added.end(), by_id);
  std::sort(cs.moved.begin(), cs.moved.end(), by_id);
  std::sort(cs.removed.begin(), cs.removed.end());
  return cs;
}

namespace detail {
/// std::invalid_argument (message starting with `who`) when an id appears twice among one
/// keyframe's ids: a keyframe observes a map point once (ORB-SLAM never repeats one), so a repeat
/// is a broken input, not a second view. `scratch` is reused between calls.
inline void check_distinct_ids(const char* who, const std::vector<std::uint64_t>& ids,
                               std::vector<std::uint64_t>& scratch) {
  scratch.assign(ids.begin(), ids.end());
  std::sort(scratch.begin(), scratch.end());
  const auto twin = std::adjacent_find(scratch.begin(), scratch.end());
  if (twin != scratch.end())
    invalid_argument(std::string(who) + ": map-point id " + std::to_string(*twin) +
                     " appears twice in one keyframe (a keyframe observes a map point once)");
}
}  // namespace detail

/// The map point cloud as the union of keyframe observations (how the paper builds it from
/// ORB-SLAM keyframes): a point with an id joins once, at its first observed position; without
/// ids every point of every keyframe is a new map point (ids 0, 1, 2, ... in arrival order).
/// A sequence must either always or never carry ids (mixing is refused: generated ids could
/// collide with real ones), and one keyframe never holds an id twice. Points with a NaN/Inf
/// coordinate are skipped and counted; an id first seen that way joins at its first finite
/// observation.
class KeyframeUnion {
 public:
  /// world: one keyframe's points in the world frame; ids: one per point, or empty.
  /// map_ids (optional): gets each point's map-point id (its own id, or the one given out), or
  /// kNoId for a point skipped as non-finite.
  ChangeSet add(const std::vector<Point3d>& world, const std::vector<std::uint64_t>& ids,
                std::vector<std::uint64_t>* map_ids = nullptr) {
    if (!world.empty()) {
      if (with_ids_ == kUnknown) with_ids_ = ids.empty() ? kNo : kYes;
      if ((with_ids_ == kYes) == ids.empty())
        detail::invalid_argument("KeyframeUnion: keyframes with and without ids are mixed");
      if (!ids.empty() && ids.size() != world.size())
        detail::invalid_argument("KeyframeUnion: one id per point expected");
      detail::check_distinct_ids("KeyframeUnion", ids, scratch_);
    }
    ChangeSet cs;
    if (map_ids) map_ids->assign(world.size(), kNoId);
    for (std::size_t j = 0; j < world.size(); ++j) {
      if (!is_finite(world[j])) {
        ++skipped_nonfinite_;
        continue;
      }
      const std::uint64_t id = ids.empty() ? next_id_++ : ids[j];
      if (map_ids) (*map_ids)[j] = id;
      if (ids.empty() || seen_.insert(id).second) cs.added.push_back({id, world[j]});
    }
    return cs;
  }
  static constexpr std::uint64_t kNoId = ~std::uint64_t{0};
  std::size_t skipped_nonfinite() const { return skipped_nonfinite_; }

 private:
  enum Mode { kUnknown, kYes, kNo };
  Mode with_ids_ = kUnknown;
  std::unordered_set<std::uint64_t> seen_;
  std::vector<std::uint64_t> scratch_;
  std::uint64_t next_id_ = 0;
  std::size_t skipped_nonfinite_ = 0;
};

/// Change detection for clouds without ids, at a voxel resolution. Keeps the cloud it has
/// reported so far (with the ids it gave out) and turns each new cloud into a ChangeSet.
class SpatialChangeDetector {
 public:
  explicit SpatialChangeDetector(double resolution, std::uint64_t first_id = 0)
      : inv_res_(1.0 / resolution), next_id_(first_id) {
    if (!(resolution > 0.0) || !std::isfinite(inv_res_))
      detail::invalid_argument("change detection resolution must be > 0");
  }

  /// The change from the previous cloud to `cloud` (points of any type; non-finite skipped).
  template <class Points>
  ChangeSet update(const Points& cloud) {
    std::unordered_set<std::uint64_t> seen;   // voxels of the new cloud
    std::unordered_set<std::uint64_t> fresh;  // of those, the ones empty before this cloud
    ChangeSet cs;
    for (const auto& p : cloud) {  // input order, so ids are given out deterministically
      const Point3d q = to_point3d(p);
      if (!is_finite(q)) continue;
      const std::uint64_t v = voxel(q);
      seen.insert(v);
      if (!fresh.count(v)) {
        if (voxels_.count(v)) continue;  // occupied before: keep the points it had
        fresh.insert(v);
      }
      cs.added.push_back({next_id_, q});
      voxels_[v].push_back(next_id_++);
    }
    for (auto it = voxels_.begin(); it != voxels_.end();) {
      if (seen.count(it->first)) {
        ++it;
        continue;
      }
      cs.removed.insert(cs.removed.end(), it->second.begin(), it->second.end());
      it = voxels_.erase(it);
    }
    std::sort(cs.removed.begin(), cs.removed.end());
    return cs;
  }

 private:
  std::uint64_t voxel(const Point3d& q) const {
    // 21 bits per axis around 0; coordinates beyond ±2^20 voxels share the edge voxel.
    auto axis = [&](double c) {
      const double f = std::floor(c * inv_res_);
      const double clamped = std::min(std::max(f, -1048576.0), 1048575.0);
      return static_cast<std::uint64_t>(static_cast<std::int64_t>(clamped) + 1048576);
    };
    return (axis(q.x) << 42) | (axis(q.y) << 21) | axis(q.z);
  }

  double inv_res_;
  std::uint64_t next_id_;
  std::unordered_map<std::uint64_t, std::vector<std::uint64_t>> voxels_;  // voxel -> ids in it
};

}  // namespace knnocc
