// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// MapPointLedger: what RobustModel (sensor/robust_model.hpp) remembers per map-point id: where
// the point is (its first world position, its voxel and that voxel's slot in the model's
// VoxelTally), which keyframes detected it, how many map points of other keyframes lie near it,
// the occupied log-odds it has put into its voxel, and the SLAM system's latest counters for it
// (core/point_evidence.hpp).
//
// Thread safety: one writer (its model).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "../core/detail/flat_index.hpp"
#include "../core/point3.hpp"
#include "../core/point_evidence.hpp"

namespace knnocc {

class MapPointLedger {
 public:
  static constexpr std::uint32_t kNone = detail::FlatIndex::kNone;

  struct Point {
    Point3d position;             ///< world position at the first observation
    std::uint64_t key = 0;        ///< its voxel (Key::pack()), when has_key
    std::uint32_t voxel = kNone;  ///< its voxel's slot in the model's VoxelTally
    bool has_key = false;         ///< inside the key range
    bool believed = false;        ///< believed real: its evidence is in the map
    std::uint32_t views = 0;      ///< keyframes that detected it
    std::uint32_t first = 0;      ///< the keyframe that detected it first (created it)
    std::uint32_t last = 0;       ///< the latest keyframe that detected it
    std::uint32_t support = 0;    ///< map points near it that other keyframes created
    /// Its detections' shares of their voxels: each detection counts 1 / (the keyframe's endpoints
    /// in that voxel), so that its evidence is that of the detections it stands for.
    float shares = 0.0f;
    float added = 0.0f;         ///< occupied log-odds it has put into its voxel (in the map)
    PointEvidence slam;         ///< the SLAM system's counters at its latest detection
    std::uint32_t bin = kNone;  ///< its counts' bin in the model's mixture
    std::uint32_t next_in_voxel = kNone;  ///< the next map point in its voxel (VoxelTally list)
    std::uint32_t touched = 0;            ///< keyframe + 1 that last changed its counts
  };

  /// The point `id` detected by keyframe `keyframe` at `p` (the first position is kept); views
  /// count once per keyframe. Returns its index; `fresh` tells whether the point is new, `counted`
  /// whether this detection counted as a view (the keyframe's first of the point).
  std::uint32_t observe(std::uint64_t id, const Point3d& p, std::uint32_t keyframe, bool& fresh,
                        bool& counted) {
    fresh = false;
    counted = false;
    const std::uint32_t i =
        index_.find_or_insert(id, static_cast<std::uint32_t>(points_.size()), fresh);
    if (fresh) {
      points_.emplace_back();
      ids_.push_back(id);
      points_.back().position = p;
      points_.back().first = keyframe;
    }
    Point& e = points_[i];
    if (fresh || e.last != keyframe) {
      ++e.views;
      e.last = keyframe;
      counted = true;
    }
    return i;
  }

  /// The ledger index of `id` (kNone when unknown); indices never change.
  std::uint32_t index_of(std::uint64_t id) const { return index_.find(id); }
  Point& at(std::uint32_t i) { return points_[i]; }
  const Point& at(std::uint32_t i) const { return points_[i]; }
  std::uint64_t id_at(std::uint32_t i) const { return ids_[i]; }

  const Point* find(std::uint64_t id) const {
    const std::uint32_t i = index_.find(id);
    return i == kNone ? nullptr : &points_[i];
  }
  Point* find(std::uint64_t id) {
    const std::uint32_t i = index_.find(id);
    return i == kNone ? nullptr : &points_[i];
  }
  std::size_t size() const { return points_.size(); }
  /// Calls f(id, point) for every map point, in the order of their first observation.
  template <class F>
  void for_each(F&& f) const {
    for (std::size_t i = 0; i < points_.size(); ++i) f(ids_[i], points_[i]);
  }
  template <class F>
  void for_each(F&& f) {
    for (std::size_t i = 0; i < points_.size(); ++i) f(ids_[i], points_[i]);
  }

 private:
  std::vector<Point> points_;
  std::vector<std::uint64_t> ids_;
  detail::FlatIndex index_;  // id -> index in points_ (ids are never 2^64-1: KeyframeUnion::kNoId)
};

}  // namespace knnocc
