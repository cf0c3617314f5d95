#pragma once
// VoxelTally: what RobustModel (sensor/robust_model.hpp) counts per voxel: how many keyframes saw
// through it, and how many of the map points in it are believed real.
//
// A keyframe sees through a voxel when one of its rays, shortened by `margin` at its end, crosses
// the voxel (OctoMap's DDA, end voxel excluded; raycast/dda.hpp): the ray went on to end more than
// `margin` beyond the voxel. Each keyframe counts once per voxel. The margin keeps a ray that ends
// on the same surface, a little behind a point, from counting against it.
//
// Voxels are kept by packed key (Key::pack()) in one open-addressing table; a voxel's slot never
// moves, so a map point keeps its voxel's slot and reads the counts without a lookup.
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
  struct Cell {
    std::uint32_t passes = 0;    ///< keyframes that saw through the voxel
    std::uint32_t believed = 0;  ///< map points in the voxel that are believed real
    std::uint32_t stamp = 0;     ///< keyframe + 1 of the latest pass
  };
  static constexpr std::uint32_t kNone = detail::FlatIndex::kNone;

  /// The slot of voxel `key` (Key::pack()), made when new.
  std::uint32_t slot(std::uint64_t key) {
    bool fresh = false;
    const std::uint32_t i =
        index_.find_or_insert(key, static_cast<std::uint32_t>(cells_.size()), fresh);
    if (fresh) cells_.push_back(Cell{});
    return i;
  }
  /// The slot of voxel `key`, or kNone.
  std::uint32_t find(std::uint64_t key) const { return index_.find(key); }
  Cell& at(std::uint32_t slot) { return cells_[slot]; }
  const Cell& at(std::uint32_t slot) const { return cells_[slot]; }

  /// Counts the rays of keyframe `keyframe` from `origin` to each points[j] with use(j), each
  /// shortened by `margin`, against the voxels they cross.
  template <class Key, class Use>
  void add_keyframe(const Grid<Key>& grid, const Point3d& origin,
                    const std::vector<Point3d>& points, double margin, std::uint32_t keyframe,
                    Use&& use) {
    const Point3f o = detail::to_point3f(origin);
    const std::uint32_t stamp = keyframe + 1;
    for (std::size_t j = 0; j < points.size(); ++j) {
      if (!use(j)) continue;
      const Point3d& p = points[j];
      const double ux = p.x - origin.x, uy = p.y - origin.y, uz = p.z - origin.z;
      const double len = std::sqrt(ux * ux + uy * uy + uz * uz);
      if (!(len > margin)) continue;
      const double f = (len - margin) / len;
      const Point3f stop =
          detail::to_point3f(Point3d{origin.x + ux * f, origin.y + uy * f, origin.z + uz * f});
      for_each_ray_key(grid, o, stop, [&](const Key& k) {
        Cell& c = cells_[slot(k.pack())];
        if (c.stamp == stamp) return;
        c.stamp = stamp;
        ++c.passes;
      });
    }
  }

  std::size_t size() const { return cells_.size(); }
  std::size_t memory_usage() const {
    return index_.memory_usage() + cells_.capacity() * sizeof(Cell);
  }

 private:
  detail::FlatIndex index_;  // packed voxel key -> slot in cells_
  std::vector<Cell> cells_;
};

}  // namespace knnocc
