// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A scan restricted to a box of keys (ScanInserter::set_clip: one tile of a larger map). Every
// voxel inside the box gets exactly the update the whole scan gives it; no voxel outside is
// touched.
//
// After phase 1 (collect) each thread's part keeps the hits inside the box, with their log-odds,
// and sorts its rays by the keys they can visit. OctoMap's walk steps every axis monotonically from
// the origin voxel towards the end voxel; float rounding may carry an axis one voxel past the end
// voxel (the dense box of a scan keeps the same one-voxel margin), never more. So a ray visits
// only keys in the box of its origin and end voxels grown by one voxel, and is
//   - dropped when that box misses the clip (it cannot touch the tile),
//   - walked as usual when that box lies inside the clip (it cannot leave the tile),
//   - else a crossing ray: walked alone, from the origin exactly as the whole scan walks it,
//     marking only the voxels inside the clip, and stopped once it has left the clip for good
//     (after entering it, or when it has passed the clip on an axis it moves along).
// Its keys are the whole walk's keys by construction; only the part before it enters the clip is
// walked without marking.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "../../core/grid.hpp"
#include "../../raycast/dda.hpp"
#include "../../raycast/detail/linear_ray.hpp"
#include "collect.hpp"

namespace knnocc::detail {

inline bool box_contains(const KeyBox& b, const std::int64_t (&k)[3]) {
  return k[0] >= b.lo[0] && k[0] <= b.hi[0] && k[1] >= b.lo[1] && k[1] <= b.hi[1] &&
         k[2] >= b.lo[2] && k[2] <= b.hi[2];
}

/// How a ray from `origin` to the voxel `end` relates to `clip`.
enum class RayClip { outside, inside, crossing };

inline RayClip classify_ray(const std::int32_t (&origin)[3], const std::int32_t (&end)[3],
                            const KeyBox& clip) {
  bool inside = true;
  for (int a = 0; a < 3; ++a) {
    const std::int64_t lo = std::int64_t{std::min(origin[a], end[a])} - 1;
    const std::int64_t hi = std::int64_t{std::max(origin[a], end[a])} + 1;
    if (hi < clip.lo[a] || lo > clip.hi[a]) return RayClip::outside;
    inside = inside && lo >= clip.lo[a] && hi <= clip.hi[a];
  }
  return inside ? RayClip::inside : RayClip::crossing;
}

/// Restricts one thread's collected part to `clip`: the hits inside it (with their log-odds, in
/// point order), the rays that stay inside it; the crossing rays are appended to `crossing`. The
/// part's key box and steps are those of what it keeps, the crossing rays' keys within the clip
/// included (so the dense box holds every voxel a crossing ray marks).
template <class Key>
void clip_part(ScanPart& part, const ScanOrigin& o, const KeyBox& clip,
               std::vector<RayEnd>& crossing) {
  KeyBox box = KeyBox::empty<Key>();
  std::size_t kept = 0;
  const bool rated = !part.hit_logodds.empty();
  for (std::size_t i = 0; i < part.hits.size(); ++i) {
    const Key k = Key::unpack(part.hits[i]);
    const std::int64_t key[3] = {k[0], k[1], k[2]};
    if (!box_contains(clip, key)) continue;
    box.extend(key);
    if (rated) part.hit_logodds[kept] = part.hit_logodds[i];
    part.hits.data()[kept++] = part.hits[i];
  }
  part.hits.set_end(part.hits.data() + kept);
  if (rated) part.hit_logodds.resize(kept);

  std::size_t steps = 0;
  kept = 0;
  RayEnd* rays = part.rays.data();
  for (std::size_t i = 0; i < part.rays.size(); ++i) {
    const RayEnd& r = rays[i];
    const RayClip c = classify_ray(o.key, r.key, clip);
    if (c == RayClip::outside) continue;
    std::int64_t lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(o.key[a], r.key[a]);
      hi[a] = std::max(o.key[a], r.key[a]);
      steps += static_cast<std::size_t>(hi[a] - lo[a]);
      if (c == RayClip::crossing) {
        lo[a] = std::max(lo[a] - 1, clip.lo[a]);
        hi[a] = std::min(hi[a] + 1, clip.hi[a]);
      }
    }
    box.extend(lo);
    box.extend(hi);
    if (c == RayClip::crossing) {
      crossing.push_back(r);
      continue;
    }
    rays[kept++] = r;
  }
  part.rays.set_end(rays + kept);
  part.box = box;
  part.steps = steps;
}

/// One crossing ray's visits: mark(position) for the voxels inside the clip; false (the walk
/// stops) once the walk can no longer reach the clip.
template <class Key, class Mark>
struct CrossingVisit {
  const KeyBox& clip;
  Mark& mark;
  bool entered = false;
  std::size_t visits = 0;

  bool operator()(const KeyPosition& p) {
    if (!p.in_range(Key::extent)) return false;
    if (box_contains(clip, p.k)) {
      entered = true;
      mark(p);
      ++visits;
      return true;
    }
    if (entered) return false;  // each axis moves one way: the walk never comes back
    for (int a = 0; a < 3; ++a) {
      const bool before = p.k[a]<clip.lo[a], after = p.k[a]> clip.hi[a];
      if ((after && p.dir[a] >= 0) || (before && p.dir[a] <= 0)) return false;
    }
    return true;
  }
};

/// A crossing ray's walk from its origin voxel (already set up in `at`, `state`); returns the
/// voxels marked.
template <class Key, class Mark>
std::size_t walk_clipped(const WalkState& state, KeyPosition at, const KeyBox& clip, Mark& mark) {
  CrossingVisit<Key, Mark> visit{clip, mark};
  if (visit(at)) walk_ray(state, at, visit);  // the origin voxel, then the walk
  return visit.visits;
}

/// Walks the crossing rays from `o` as OctoMap's walk does, calling mark(position) for every
/// voxel inside `clip` (KeyPosition: per-axis keys); returns the voxels marked.
template <class Key, class Mark>
std::size_t walk_crossing(const Grid<Key>& grid, const ScanOrigin& o,
                          const std::vector<RayEnd>& rays, const KeyBox& clip, Mark&& mark) {
  std::size_t visits = 0;
  for (const RayEnd& r : rays) {
    int step[3];
    WalkState state;
    setup_walk(grid, o.point, r.end, o.key, r.key, step, state);
    const KeyPosition at{{o.key[0], o.key[1], o.key[2]},
                         {step[0], step[1], step[2]},
                         {r.key[0], r.key[1], r.key[2]}};
    visits += walk_clipped<Key>(state, at, clip, mark);
  }
  return visits;
}

/// for_each_ray_key(grid, origin, end, visit) restricted to the keys inside `clip`: a ray that
/// cannot reach the clip is not walked, one that cannot leave it is walked as usual, and a
/// crossing ray from its origin until it leaves the clip for good.
template <class Key, class Visit>
void for_each_ray_key_in(const Grid<Key>& grid, const Point3f& origin, const Point3f& end,
                         const KeyBox& clip, Visit&& visit) {
  RayWalk<Key> w;
  if (start_ray(grid, origin, end, w) != RayStart::walk) return;
  std::int32_t ko[3], ke[3];
  for (int a = 0; a < 3; ++a) {
    ko[a] = static_cast<std::int32_t>(w.origin[a]);
    ke[a] = static_cast<std::int32_t>(w.end[a]);
  }
  const RayClip c = classify_ray(ko, ke, clip);
  if (c == RayClip::outside) return;
  using I = typename Key::index_type;
  auto mark = [&](const KeyPosition& p) {
    visit(Key(static_cast<I>(p.k[0]), static_cast<I>(p.k[1]), static_cast<I>(p.k[2])));
  };
  const KeyPosition at{
      {ko[0], ko[1], ko[2]}, {w.step[0], w.step[1], w.step[2]}, {ke[0], ke[1], ke[2]}};
  if (c == RayClip::crossing) {
    walk_clipped<Key>(w.state, at, clip, mark);
    return;
  }
  KeyPosition pos = at;
  mark(pos);
  walk_ray(w.state, pos, [&](const KeyPosition& p) {
    if (!p.in_range(Key::extent)) return false;
    mark(p);
    return true;
  });
}

}  // namespace knnocc::detail
