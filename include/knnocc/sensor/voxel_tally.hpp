// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// VoxelTally: what RobustModel (sensor/robust_model.hpp) counts per voxel: how many keyframes saw
// through it and, for a voxel holding map points, how many of them are believed real.
//
// A keyframe sees through a voxel when one of its rays, shortened by `margin` at its end, crosses
// the voxel (OctoMap's DDA, end voxel excluded; raycast/dda.hpp): the ray went on to end more than
// `margin` beyond the voxel. Each keyframe counts once per voxel. The margin keeps a ray that ends
// on the same surface, a little behind a point, from counting against it.
// With witnesses (the map point each ray ends at), a voxel that holds map points counts a
// keyframe's see-through only when one of its rays through the voxel ends at a map point that has
// not seen through the voxel before: a point that keyframe after keyframe re-detects is one
// witness against what lies in front of it, not one per keyframe (its re-detections are the same
// match, not independent looks; a wrong match re-detected behind a real surface otherwise makes
// the surface look seen through as often as the match is re-detected).
//
// Storage: see-throughs in bricks of 8x8x8 voxels found by packed brick key (a ray's consecutive
// voxels mostly share a brick, so a walk looks up about one brick per eight voxels); voxels that
// hold map points also get a cell (believed count, the list of their points) whose slot never
// moves, so a map point reads its voxel's counts without a lookup.
//
// Thread safety: one writer.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "../core/detail/flat_index.hpp"
#include "../core/grid.hpp"
#include "../core/point3.hpp"
#include "../raycast/dda.hpp"

namespace knnocc {

class VoxelTally {
 public:
  static constexpr std::uint32_t kNone = detail::FlatIndex::kNone;
  /// A voxel that holds map points.
  struct Cell {
    std::uint32_t believed = 0;  ///< its map points that are believed real
    /// Its map points, a list through the owner's points (MapPointLedger::Point::next_in_voxel).
    std::uint32_t first_point = kNone;
    std::uint32_t pass = 0;  ///< its see-through counter (passes_ index)
  };

  /// The cell of voxel `key` (Key::pack()), made when new.
  template <class Key>
  std::uint32_t slot(const Key& key) {
    Pass& q = passes_[pass_index(key)];
    if (q.cell == kNone) {
      q.cell = static_cast<std::uint32_t>(cells_.size());
      cells_.push_back(Cell{0, kNone, pass_index(key)});
    }
    return q.cell;
  }
  Cell& at(std::uint32_t slot) { return cells_[slot]; }
  const Cell& at(std::uint32_t slot) const { return cells_[slot]; }
  /// Keyframes that saw through the voxel of cell `slot`.
  std::uint32_t passes_at(std::uint32_t slot) const { return passes_[cells_[slot].pass].passes; }
  /// Keyframes that saw through voxel `key` (0 for a voxel no ray reached).
  template <class Key>
  std::uint32_t passes(const Key& key) const {
    const std::uint32_t b = bricks_.find(brick_key(key));
    return b == kNone ? 0 : passes_[b * kBrickVoxels + local(key)].passes;
  }
  /// The cell of voxel `key`, or kNone.
  template <class Key>
  std::uint32_t find(const Key& key) const {
    const std::uint32_t b = bricks_.find(brick_key(key));
    return b == kNone ? kNone : passes_[b * kBrickVoxels + local(key)].cell;
  }

  /// Counts the rays of keyframe `keyframe` from `origin` to each points[j] with use(j), each
  /// shortened by `margin`, against the voxels they cross; on_pass(slot) for each voxel with a
  /// cell that the keyframe newly saw through.
  template <class Key, class Use, class OnPass>
  void add_keyframe(const Grid<Key>& grid, const Point3d& origin,
                    const std::vector<Point3d>& points, double margin, std::uint32_t keyframe,
                    Use&& use, OnPass&& on_pass) {
    add_keyframe(
        grid, origin, points, margin, keyframe, use, [](std::size_t) { return kNone; }, on_pass,
        [](std::size_t, std::uint32_t) {});
  }
  /// The same with witnesses: witness(j) is the map point ray j ends at (an index below kNone),
  /// or kNone for a ray that counts as before; and on_cross(j, slot) for every voxel with a cell
  /// that ray j crosses (counted or not).
  template <class Key, class Use, class Witness, class OnPass, class OnCross>
  void add_keyframe(const Grid<Key>& grid, const Point3d& origin,
                    const std::vector<Point3d>& points, double margin, std::uint32_t keyframe,
                    Use&& use, Witness&& witness, OnPass&& on_pass, OnCross&& on_cross) {
    const Point3f o = detail::to_point3f(origin);
    const std::uint32_t stamp = keyframe + 1;
    std::uint64_t last_brick = ~std::uint64_t{0};
    std::uint32_t base = 0;
    for (std::size_t j = 0; j < points.size(); ++j) {
      if (!use(j)) continue;
      const std::uint32_t w = witness(j);
      const Point3d& p = points[j];
      const double ux = p.x - origin.x, uy = p.y - origin.y, uz = p.z - origin.z;
      const double len = std::sqrt(ux * ux + uy * uy + uz * uz);
      if (!(len > margin)) continue;
      const double f = (len - margin) / len;
      const Point3f stop =
          detail::to_point3f(Point3d{origin.x + ux * f, origin.y + uy * f, origin.z + uz * f});
      for_each_ray_key(grid, o, stop, [&](const Key& k) {
        const std::uint64_t bk = brick_key(k);
        if (bk != last_brick) {
          base = brick(bk) * kBrickVoxels;
          last_brick = bk;
        }
        Pass& q = passes_[base + local(k)];
        if (q.cell != kNone) on_cross(j, q.cell);
        if (q.cell != kNone && w != kNone) {  // a witness counts once per voxel
          bool fresh = false;
          witnesses_.find_or_insert(std::uint64_t{q.cell} << 32 | w, 0, fresh);
          if (!fresh) return;
        }
        if (q.stamp == stamp) return;
        q.stamp = stamp;
        ++q.passes;
        if (q.cell != kNone) on_pass(q.cell);
      });
    }
  }

  /// Voxels with a cell.
  std::size_t size() const { return cells_.size(); }
  std::size_t memory_usage() const {
    return bricks_.memory_usage() + passes_.capacity() * sizeof(Pass) +
           cells_.capacity() * sizeof(Cell) + witnesses_.memory_usage();
  }

 private:
  static constexpr std::uint32_t kBrickVoxels = 512;
  struct Pass {
    std::uint32_t passes = 0;  // keyframes that saw through the voxel
    std::uint32_t stamp = 0;   // keyframe + 1 of the latest pass
    std::uint32_t cell = kNone;
  };
  template <class Key>
  static std::uint64_t brick_key(const Key& k) {
    return std::uint64_t{k[0]} >> 3 | (std::uint64_t{k[1]} >> 3) << 21 |
           (std::uint64_t{k[2]} >> 3) << 42;
  }
  template <class Key>
  static std::uint32_t local(const Key& k) {
    return (std::uint32_t{k[0]} & 7) | (std::uint32_t{k[1]} & 7) << 3 |
           (std::uint32_t{k[2]} & 7) << 6;
  }
  std::uint32_t brick(std::uint64_t bk) {
    bool fresh = false;
    const std::uint32_t b = bricks_.find_or_insert(
        bk, static_cast<std::uint32_t>(passes_.size() / kBrickVoxels), fresh);
    if (fresh) passes_.resize(passes_.size() + kBrickVoxels);
    return b;
  }
  template <class Key>
  std::uint32_t pass_index(const Key& k) {
    return brick(brick_key(k)) * kBrickVoxels + local(k);
  }

  detail::FlatIndex bricks_;  // packed brick key -> brick number (its Pass block in passes_)
  std::vector<Pass> passes_;
  std::vector<Cell> cells_;
  detail::FlatIndex witnesses_;  // (cell << 32 | witness) pairs seen (add_keyframe)
};

}  // namespace knnocc
