// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The crossing rays of a clipped scan (clip.hpp: rays from outside the clip that reach it) walked
// into a thread's dense miss bitmap, for ScanInserter.

#include <cstddef>

#include "../../core/grid.hpp"
#include "../../raycast/dda.hpp"
#include "../../raycast/detail/fan_walk.hpp"
#include "../../raycast/detail/linear_ray.hpp"
#include "clip.hpp"
#include "collect.hpp"
#include "thread_scratch.hpp"

namespace knnocc::detail {

// Returns the voxels visited. With a clip of whole bricks (`whole_bricks`) each ray jumps to its
// first voxel inside the clip and is walked on from there to its end on the fast path, in a box
// that holds that rest (the apply leaves out the bricks past the clip); otherwise each marks only
// the voxels inside.
template <class Key, class Marks>
std::size_t walk_crossing_marks(const Grid<Key>& grid, ThreadScratch& mine, const ScanOrigin& o,
                                const RayFan& fan, const KeyBox& clip, bool whole_bricks,
                                Marks marks) {
  const ScanBitmap& miss = mine.miss;
  auto mark = [&](const KeyPosition& p) { marks(miss.index(p.k[0], p.k[1], p.k[2])); };
  if (!whole_bricks) return walk_crossing(grid, o, mine.crossing, clip, mark);
  std::size_t visits = 0, next_ray = 0;
  LinearRay ray;
  auto next = [&]() -> const LinearRay* {
    while (next_ray < mine.crossing.size()) {
      const RayEnd& r = mine.crossing[next_ray++];
      int step[3];
      setup_walk(grid, o.point, r.end, o.key, r.key, step, ray.state);
      KeyPosition at{{o.key[0], o.key[1], o.key[2]},
                     {step[0], step[1], step[2]},
                     {r.key[0], r.key[1], r.key[2]}};
      const WalkState whole = ray.state;
      switch (jump_to_entry(ray.state, at, clip)) {
        case Entry::never:
          continue;
        case Entry::walk:  // the entry at the ray's very end: walked one voxel at a time
          visits += walk_clipped<Key>(whole, at, clip, mark);
          continue;
        case Entry::jumped:
          break;
      }
      ray.index = miss.index(at.k[0], at.k[1], at.k[2]);
      ray.end_index = miss.index(r.key[0], r.key[1], r.key[2]);
      for (int a = 0; a < 3; ++a) ray.stride[a] = step[a] * miss.stride(a);
      ray.clear_end = end_point_clear<Key>(fan, r, whole.length);
      return &ray;
    }
    return nullptr;
  };
  const std::size_t walked = walk_linear_rays(best_walk_path<Marks>(), next, marks);
  return visits + walked;
}

template <class Key>
std::size_t walk_crossing_dense(const Grid<Key>& grid, ThreadScratch& mine, const ScanOrigin& o,
                                const RayFan& fan, const KeyBox& clip, bool whole_bricks) {
  ScanBitmap& miss = mine.miss;
  if (miss.has_bytes())
    return walk_crossing_marks(grid, mine, o, fan, clip, whole_bricks, ByteMarks{miss.bytes()});
  return walk_crossing_marks(grid, mine, o, fan, clip, whole_bricks, BitMarks{miss.words()});
}

}  // namespace knnocc::detail
