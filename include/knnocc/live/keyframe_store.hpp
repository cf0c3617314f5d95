// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The live mapper's keyframes, in insertion order: id, pose, sensor-frame points (float, 12
// bytes each), map-point ids (k-NN model only, 8 bytes each) and the box of map bricks its rays
// can reach (the per-keyframe bounding-box index that tells which keyframes a region needs).
//
// BrickBox is conservative: it holds every brick a keyframe's rays touch, computed from the
// sensor position and the end points (those beyond max_range clamped into the cube of half edge
// max_range around the sensor, which holds their truncated rays), one voxel of margin for the
// float rounding of the key computation, clipped to the key range.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

#include "../core/config.hpp"
#include "../core/point3.hpp"
#include "../map/brick.hpp"

namespace knnocc {

/// An inclusive box of brick coordinates (a brick is 8x8x8 voxels); empty when lo > hi.
struct BrickBox {
  std::array<std::int64_t, 3> lo{1, 1, 1}, hi{0, 0, 0};

  bool empty() const { return lo[0] > hi[0] || lo[1] > hi[1] || lo[2] > hi[2]; }
  bool intersects(const BrickBox& o) const {
    if (empty() || o.empty()) return false;
    for (int a = 0; a < 3; ++a)
      if (lo[a] > o.hi[a] || o.lo[a] > hi[a]) return false;
    return true;
  }
  bool contains(const std::array<std::int64_t, 3>& b) const {
    for (int a = 0; a < 3; ++a)
      if (b[a] < lo[a] || b[a] > hi[a]) return false;
    return true;
  }
  /// Bricks in the box (0 when empty).
  double volume() const {
    if (empty()) return 0.0;
    double v = 1.0;
    for (int a = 0; a < 3; ++a) v *= static_cast<double>(hi[a] - lo[a] + 1);
    return v;
  }
};

namespace detail {
// The brick box of the world-coordinate extent [lo, hi], one voxel of margin, clipped to the keys.
template <class Key>
BrickBox brick_box(const double lo[3], const double hi[3], double resolution) {
  BrickBox box;
  const double top = static_cast<double>(2 * Key::center - 1);
  for (int a = 0; a < 3; ++a) {
    const double l = std::clamp(std::floor(lo[a] / resolution) - 1.0 + Key::center, 0.0, top);
    const double h = std::clamp(std::floor(hi[a] / resolution) + 1.0 + Key::center, 0.0, top);
    box.lo[a] = static_cast<std::int64_t>(l) >> kBrickBits;
    box.hi[a] = static_cast<std::int64_t>(h) >> kBrickBits;
  }
  return box;
}
}  // namespace detail

/// Where one ray can reach: the ray from origin o towards p (within the max-range cube).
struct RayReach {
  double o[3] = {0, 0, 0};
  double max_range = -1.0;

  RayReach(const Point3d& origin, double range)
      : o{origin.x, origin.y, origin.z}, max_range(range) {}
  /// false for a non-finite p (such a point casts no ray); else lo/hi hold the extent.
  bool extent(const Point3d& p, double lo[3], double hi[3]) const {
    const double c[3] = {p.x, p.y, p.z};
    if (!std::isfinite(c[0]) || !std::isfinite(c[1]) || !std::isfinite(c[2])) return false;
    for (int a = 0; a < 3; ++a) {
      double v = c[a];
      if (max_range > 0.0) v = std::clamp(v, o[a] - max_range, o[a] + max_range);
      lo[a] = std::min(o[a], v);
      hi[a] = std::max(o[a], v);
    }
    return true;
  }
};

/// The bricks that rays from `origin` to `world` can touch, for keys of type Key at `resolution`.
template <class Key>
BrickBox reach_of(const Point3d& origin, const std::vector<Point3d>& world, double resolution,
                  double max_range) {
  const RayReach ray(origin, max_range);
  double lo[3] = {origin.x, origin.y, origin.z}, hi[3] = {origin.x, origin.y, origin.z};
  bool any = false;
  for (const Point3d& p : world) {
    double l[3], h[3];
    if (!ray.extent(p, l, h)) continue;
    any = true;
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], l[a]);
      hi[a] = std::max(hi[a], h[a]);
    }
  }
  if (!any) return BrickBox{};  // no rays: the keyframe touches nothing
  return detail::brick_box<Key>(lo, hi, resolution);
}

/// One stored keyframe.
template <class Pose>
struct LiveKeyframe {
  std::uint64_t id = 0;
  Pose pose;
  std::vector<Point3f> points;     ///< sensor frame
  std::vector<std::uint64_t> ids;  ///< map-point ids (k-NN model), or empty
  BrickBox reach;                  ///< with the current pose
};

/// Keyframes in insertion order with an id index.
template <class Pose>
class KeyframeStore {
 public:
  using keyframe_type = LiveKeyframe<Pose>;

  std::size_t size() const { return frames_.size(); }
  bool contains(std::uint64_t id) const { return index_.count(id) > 0; }
  /// Position in insertion order; the id must be stored.
  std::size_t position(std::uint64_t id) const { return index_.at(id); }
  keyframe_type& operator[](std::size_t i) { return frames_[i]; }
  const keyframe_type& operator[](std::size_t i) const { return frames_[i]; }
  const std::vector<keyframe_type>& frames() const { return frames_; }

  void push_back(keyframe_type kf) {
    index_.emplace(kf.id, frames_.size());
    frames_.push_back(std::move(kf));
  }
  /// Removes the keyframes whose `doomed` flag is set; order of the rest is kept.
  void erase(const std::vector<char>& doomed) {
    std::size_t kept = 0;
    for (std::size_t i = 0; i < frames_.size(); ++i)
      if (!doomed[i]) {
        if (kept != i) frames_[kept] = std::move(frames_[i]);
        ++kept;
      }
    frames_.resize(kept);
    index_.clear();
    for (std::size_t i = 0; i < frames_.size(); ++i) index_.emplace(frames_[i].id, i);
  }
  /// Points stored (all keyframes).
  std::size_t points() const {
    std::size_t n = 0;
    for (const keyframe_type& kf : frames_) n += kf.points.size();
    return n;
  }
  /// Bytes held by the stored keyframes (points, ids, poses, boxes, the id index).
  std::size_t memory_usage() const {
    std::size_t bytes = frames_.capacity() * sizeof(keyframe_type);
    for (const keyframe_type& kf : frames_)
      bytes += kf.points.capacity() * sizeof(Point3f) + kf.ids.capacity() * sizeof(std::uint64_t);
    bytes += index_.size() * (sizeof(std::pair<std::uint64_t, std::size_t>) + 2 * sizeof(void*)) +
             index_.bucket_count() * sizeof(void*);
    return bytes;
  }

 private:
  std::vector<keyframe_type> frames_;
  std::unordered_map<std::uint64_t, std::size_t> index_;
};

}  // namespace knnocc
