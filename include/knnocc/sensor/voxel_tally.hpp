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
// Storage: see-throughs in bricks of 8x8x8 voxels found by packed brick key; voxels that hold map
// points also get a cell (believed count, the list of their points) whose slot never moves, so a
// map point reads its voxel's counts without a lookup.
//
// Walks: a keyframe's rays go into a dense bitmap of their box on the scan inserter's vector walks
// (raycast/detail/fan_walk.hpp: exactly walk_ray()'s voxels), and each voxel of the bitmap adds
// its pass a brick at a time. The rays that may cross a cell the bitmap holds (by their distance
// to it) are walked again one at a time, each up to the farthest such cell, so that witnesses and
// on_cross() meet each ray's cells in the order of a ray-by-ray walk. A box the bitmap does not
// suit (too large for its rays, or at the edge of the key range) takes the ray-by-ray walk on
// hashed bricks; both count alike (tests compare them).
//
// Thread safety: one writer.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "../core/detail/flat_index.hpp"
#include "../core/grid.hpp"
#include "../core/point3.hpp"
#include "../map/brick.hpp"
#include "../raycast/dda.hpp"
#include "../raycast/detail/fan_walk.hpp"
#include "../raycast/detail/scan_bitmap.hpp"

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
    stops_.clear();
    for (std::size_t j = 0; j < points.size(); ++j) {
      if (!use(j)) continue;
      const Point3d& p = points[j];
      const double ux = p.x - origin.x, uy = p.y - origin.y, uz = p.z - origin.z;
      const double len = std::sqrt(ux * ux + uy * uy + uz * uz);
      if (!(len > margin)) continue;
      const double f = (len - margin) / len;
      stops_.push_back(Stop{
          j, detail::to_point3f(Point3d{origin.x + ux * f, origin.y + uy * f, origin.z + uz * f})});
    }
    const std::uint32_t stamp = keyframe + 1;
    if (dense_walk_ && walk_dense(grid, o, stamp, witness, on_pass, on_cross)) return;
    walk_hashed(grid, o, stamp, witness, on_pass, on_cross);
  }

  /// Whether add_keyframe may walk a keyframe's rays into a dense bitmap (the default) or walks
  /// every ray on hashed bricks (tests compare the two).
  void set_dense_walk(bool on) { dense_walk_ = on; }

  /// Voxels with a cell.
  std::size_t size() const { return cells_.size(); }
  std::size_t memory_usage() const {
    return bricks_.memory_usage() + passes_.capacity() * sizeof(Pass) +
           cells_.capacity() * sizeof(Cell) + witnesses_.memory_usage() +
           stops_.capacity() * sizeof(Stop) + scratch_.memory_usage();
  }

 private:
  // A ray to walk: its point's index and its end, shortened by the margin.
  struct Stop {
    std::size_t j;
    Point3f end;
  };
  // Ray j crosses a cell at its step-th voxel.
  struct Crossing {
    std::size_t j;
    std::uint32_t step, cell;
  };
  // A cell the keyframe's rays reached: its voxel, the step at which a walk could stand on it
  // (its L1 key distance from the origin's voxel) and its centre.
  struct SeenCell {
    std::uint32_t cell, step;
    std::uint64_t packed;
    std::int64_t key[3];
    Point3d centre;
  };
  // The dense walk's scratch, kept between keyframes for its memory; a copy starts empty.
  struct Scratch {
    detail::ScanBitmap seen;
    std::unique_ptr<detail::RayBlock> block;
    std::vector<detail::RayEnd> ends;    // the rays that leave the origin's voxel
    std::vector<std::uint32_t> stop_of;  // ends[i] is stops_[stop_of[i]]
    std::vector<VoxelMask> masks;
    std::vector<SeenCell> cells;
    std::vector<const SeenCell*> near;  // the cells a ray may cross
    std::vector<Crossing> crossings;

    Scratch() = default;
    Scratch(const Scratch&) : Scratch() {}
    Scratch& operator=(const Scratch&) { return *this; }
    Scratch(Scratch&&) = default;
    Scratch& operator=(Scratch&&) = default;
    ~Scratch() = default;
    std::size_t memory_usage() const {
      return seen.capacity_bytes() + (block ? sizeof(detail::RayBlock) : 0) +
             ends.capacity() * sizeof(detail::RayEnd) + stop_of.capacity() * sizeof(std::uint32_t) +
             masks.capacity() * sizeof(VoxelMask) + cells.capacity() * sizeof(SeenCell) +
             near.capacity() * sizeof(SeenCell*) + crossings.capacity() * sizeof(Crossing);
    }
  };
  // The dense walk's box of keys [lo, lo + size).
  struct Box {
    std::int64_t lo[3], size[3];
  };
  // Voxels of a box at most: a 4 MB bitmap.
  static constexpr std::int64_t kMaxBoxVoxels = std::int64_t{32} << 20;

  // Ray j crosses cell `cell`: on_cross, then a pass unless the ray's witness has seen through
  // the voxel before or the keyframe has passed it already.
  template <class Witness, class OnPass, class OnCross>
  void cross_cell(std::size_t j, std::uint32_t cell, std::uint32_t stamp, Witness& witness,
                  OnPass& on_pass, OnCross& on_cross) {
    on_cross(j, cell);
    const std::uint32_t w = witness(j);
    if (w != kNone) {  // a witness counts once per voxel
      bool fresh = false;
      witnesses_.find_or_insert(std::uint64_t{cell} << 32 | w, 0, fresh);
      if (!fresh) return;
    }
    Pass& q = passes_[cells_[cell].pass];
    if (q.stamp == stamp) return;
    q.stamp = stamp;
    ++q.passes;
    on_pass(cell);
  }

  // Every ray, one at a time, on hashed bricks.
  template <class Key, class Witness, class OnPass, class OnCross>
  void walk_hashed(const Grid<Key>& grid, const Point3f& o, std::uint32_t stamp, Witness& witness,
                   OnPass& on_pass, OnCross& on_cross) {
    std::uint64_t last_brick = ~std::uint64_t{0};
    std::uint32_t base = 0;
    for (const Stop& s : stops_)
      for_each_ray_key(grid, o, s.end, [&](const Key& k) {
        const std::uint64_t bk = brick_key(k);
        if (bk != last_brick) {
          base = brick(bk) * kBrickVoxels;
          last_brick = bk;
        }
        Pass& q = passes_[base + local(k)];
        if (q.cell != kNone) {
          cross_cell(s.j, q.cell, stamp, witness, on_pass, on_cross);
          return;
        }
        if (q.stamp == stamp) return;
        q.stamp = stamp;
        ++q.passes;
      });
  }

  // The rays into a dense bitmap of their box, a pass for each voxel of it, then the cells'
  // crossings ray by ray; false (nothing counted) when the box does not suit a bitmap.
  template <class Key, class Witness, class OnPass, class OnCross>
  bool walk_dense(const Grid<Key>& grid, const Point3f& o, std::uint32_t stamp, Witness& witness,
                  OnPass& on_pass, OnCross& on_cross) {
    Key ko;
    if (!grid.point_to_key(o, ko)) return false;
    const std::optional<Box> box = plan_box(grid, ko);
    if (!box) return false;
    if (scratch_.ends.empty()) return true;
    detail::ScanBitmap& seen = scratch_.seen;
    seen.reshape(box->lo, box->size, false);
    const std::int32_t kof[3] = {static_cast<std::int32_t>(ko[0]), static_cast<std::int32_t>(ko[1]),
                                 static_cast<std::int32_t>(ko[2])};
    const detail::RayFan fan(grid, o, kof, box->lo,
                             {seen.stride(0), seen.stride(1), seen.stride(2)});
    if (!scratch_.block) scratch_.block = std::make_unique<detail::RayBlock>();
    bool handed = false;
    auto more = [&](const detail::RayEnd*& pos, const detail::RayEnd*& end) {
      if (handed) return false;
      handed = true;
      pos = scratch_.ends.data();
      end = pos + scratch_.ends.size();
      return true;
    };
    detail::walk_fan(detail::best_walk_path<detail::BitMarks>(), grid, fan, *scratch_.block, more,
                     detail::BitMarks{seen.words()});
    count_seen<Key>();
    cross_cells(grid, o, ko, stamp, witness, on_pass, on_cross);
    return true;
  }

  // The dense box of the rays that leave the origin's voxel `ko` (into scratch_.ends), shaped as
  // the scan inserter's (detail::dense_box_shape) and as sparse at most (kDenseBitsPerStep);
  // nullopt when a ray ends outside the key range or the box does not suit a bitmap.
  template <class Key>
  std::optional<Box> plan_box(const Grid<Key>& grid, const Key& ko) {
    std::int64_t lo[3], hi[3];
    for (int a = 0; a < 3; ++a) lo[a] = hi[a] = ko[a];
    scratch_.ends.clear();
    scratch_.stop_of.clear();
    std::size_t steps = 0;
    for (std::size_t i = 0; i < stops_.size(); ++i) {
      Key ke;
      if (!grid.point_to_key(stops_[i].end, ke)) return std::nullopt;
      if (ke == ko) continue;  // a ray within one voxel visits none
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min<std::int64_t>(lo[a], ke[a]);
        hi[a] = std::max<std::int64_t>(hi[a], ke[a]);
        steps += static_cast<std::size_t>(std::llabs(std::int64_t{ke[a]} - ko[a]));
      }
      scratch_.ends.push_back(
          detail::RayEnd{stops_[i].end,
                         {static_cast<std::int32_t>(ke[0]), static_cast<std::int32_t>(ke[1]),
                          static_cast<std::int32_t>(ke[2])}});
      scratch_.stop_of.push_back(static_cast<std::uint32_t>(i));
    }
    Box box;
    std::int64_t voxels = 0;
    if (!detail::dense_box_shape<Key>(lo, hi, box.lo, box.size, voxels) || voxels > kMaxBoxVoxels ||
        voxels >
            detail::kDenseBitsPerStep * static_cast<std::int64_t>(steps) + (std::int64_t{1} << 20))
      return std::nullopt;
    return box;
  }

  // A pass for each voxel of the bitmap but the cells (remembered in scratch_.cells); clears the
  // bitmap.
  template <class Key>
  void count_seen() {
    detail::ScanBitmap& seen = scratch_.seen;
    scratch_.cells.clear();
    scratch_.masks.resize(static_cast<std::size_t>(seen.bricks(0)));
    for (std::int64_t bz = 0; bz < seen.bricks(2); ++bz)
      for (std::int64_t by = 0; by < seen.bricks(1); ++by) {
        for (VoxelMask& m : scratch_.masks) m.clear();
        seen.take_brick_row(by, bz, scratch_.masks.data());
        for (std::int64_t bx = 0; bx < seen.bricks(0); ++bx) {
          const VoxelMask& m = scratch_.masks[static_cast<std::size_t>(bx)];
          if (!m.any()) continue;
          const std::int64_t b[3] = {bx, by, bz};
          typename Key::index_type corner[3];
          for (int a = 0; a < 3; ++a)
            corner[a] = static_cast<typename Key::index_type>(seen.lo()[a] + b[a] * kBrickEdge);
          const Key first(corner[0], corner[1], corner[2]);
          const std::uint32_t base = brick(brick_key(first)) * kBrickVoxels;
          m.for_each([&](int i) {
            Pass& q = passes_[base + static_cast<std::uint32_t>(i)];
            if (q.cell != kNone) {
              const Key k(static_cast<typename Key::index_type>(corner[0] + (i & 7)),
                          static_cast<typename Key::index_type>(corner[1] + (i >> 3 & 7)),
                          static_cast<typename Key::index_type>(corner[2] + (i >> 6)));
              scratch_.cells.push_back(SeenCell{q.cell, 0, k.pack(), {k[0], k[1], k[2]}, {}});
              return;
            }
            ++q.passes;  // once: the bitmap holds each voxel once (no stamp needed)
          });
        }
      }
    seen.mark_clean();
  }

  // The crossings of the cells seen, in the order of a ray-by-ray walk; then cross_cell() for
  // each. A walk steps one voxel along one axis at a time and never back, so it can stand on a
  // voxel only at the step equal to the voxel's L1 key distance from the origin's voxel, and only
  // if the voxel lies within a voxel of its segment (every voxel it visits lies within half a
  // diagonal) and in the key box of its two end voxels grown by one (it may pass the end voxel's
  // border by rounding, never a second one: insertion/detail/dense_box.hpp). Each ray with such
  // cells is walked once, up to the step of the farthest.
  template <class Key, class Witness, class OnPass, class OnCross>
  void cross_cells(const Grid<Key>& grid, const Point3f& o, const Key& ko, std::uint32_t stamp,
                   Witness& witness, OnPass& on_pass, OnCross& on_cross) {
    if (scratch_.cells.empty()) return;
    for (SeenCell& c : scratch_.cells) {
      const Key k = Key::unpack(c.packed);
      c.step = 0;
      for (int a = 0; a < 3; ++a) c.step += static_cast<std::uint32_t>(std::abs(c.key[a] - ko[a]));
      c.centre =
          Point3d{grid.index_to_coord(k[0]), grid.index_to_coord(k[1]), grid.index_to_coord(k[2])};
    }
    std::vector<Crossing>& crossings = scratch_.crossings;
    std::vector<const SeenCell*>& near = scratch_.near;
    crossings.clear();
    const double r2 = grid.resolution() * grid.resolution();
    for (std::size_t r = 0; r < scratch_.ends.size(); ++r) {
      const detail::RayEnd& e = scratch_.ends[r];
      const Stop& s = stops_[scratch_.stop_of[r]];
      near.clear();
      for (const SeenCell& c : scratch_.cells) {
        bool in_box = true;
        for (int a = 0; a < 3; ++a)
          in_box = in_box && c.key[a] >= std::min<std::int64_t>(ko[a], e.key[a]) - 1 &&
                   c.key[a] <= std::max<std::int64_t>(ko[a], e.key[a]) + 1;
        if (in_box && segment_distance2(o, s.end, c.centre) <= r2) near.push_back(&c);
      }
      if (near.empty()) continue;
      std::sort(near.begin(), near.end(),
                [](const SeenCell* x, const SeenCell* y) { return x->step < y->step; });
      walk_to_cells(grid, o, s, near, crossings);
    }
    for (const Crossing& x : crossings) cross_cell(x.j, x.cell, stamp, witness, on_pass, on_cross);
  }

  // Walks ray s up to the step of the last of `near` (sorted by step) and adds its crossings of
  // them.
  template <class Key>
  static void walk_to_cells(const Grid<Key>& grid, const Point3f& o, const Stop& s,
                            const std::vector<const SeenCell*>& near,
                            std::vector<Crossing>& crossings) {
    const std::uint32_t last = near.back()->step;
    std::size_t next = 0;
    std::uint32_t step = 0;
    for_each_ray_key(grid, o, s.end, [&](const Key& k) {
      while (next < near.size() && near[next]->step < step) ++next;
      for (std::size_t i = next; i < near.size() && near[i]->step == step; ++i)
        if (near[i]->packed == k.pack()) crossings.push_back(Crossing{s.j, step, near[i]->cell});
      return step++ < last;
    });
  }

  // Squared distance from c to the segment a -> b.
  static double segment_distance2(const Point3f& a, const Point3f& b, const Point3d& c) {
    const double ux = double{b.x} - a.x, uy = double{b.y} - a.y, uz = double{b.z} - a.z;
    const double wx = c.x - a.x, wy = c.y - a.y, wz = c.z - a.z;
    const double uu = ux * ux + uy * uy + uz * uz;
    const double t = uu > 0 ? std::clamp((wx * ux + wy * uy + wz * uz) / uu, 0.0, 1.0) : 0.0;
    const double dx = wx - t * ux, dy = wy - t * uy, dz = wz - t * uz;
    return dx * dx + dy * dy + dz * dz;
  }

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
  std::vector<Stop> stops_;      // the keyframe's rays (kept for the memory)
  Scratch scratch_;
  bool dense_walk_ = true;
};

}  // namespace knnocc
