// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A scan restricted to a box of keys (ScanInserter::set_clip: one tile of a larger map). Every
// voxel inside the box gets exactly the update the whole scan gives it; no voxel outside is
// touched.
//
// After phase 1 (collect) each thread's part keeps the hits inside the box, with their log-odds.
// A scan whose origin lies inside a box of whole bricks (a tile) walks its rays whole, as
// unclipped, and the apply leaves out the bricks outside the box. Otherwise the rays are sorted by
// the keys they can visit: OctoMap's walk steps every axis monotonically from
// the origin voxel towards the end voxel; float rounding may carry an axis one voxel past the end
// voxel (the dense box of a scan keeps the same one-voxel margin), never more. So a ray visits
// only keys in the box of its origin and end voxels grown by one voxel, and is
//   - dropped when that box misses the clip (it cannot touch the tile),
//   - walked as usual when that box lies inside the clip (it cannot leave the tile),
//   - else a crossing ray: moved to its first voxel inside the clip with the exact state the walk
//     has there (jump_to_entry, without walking the voxels before it), walked on marking the
//     voxels inside, and stopped once it has left the clip for good.
// Its keys are the whole walk's keys by construction.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "../../core/grid.hpp"
#include "../../map/brick.hpp"
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

/// `past`: how far the walk may go past the end voxel, 1 or 0 (an end point clear of its voxel's
/// borders, end_point_clear: the walk then ends on the end voxel). The walk never moves back past
/// the origin voxel.
inline RayClip classify_ray(const std::int32_t (&origin)[3], const std::int32_t (&end)[3],
                            const KeyBox& clip, int past = 1) {
  bool inside = true;
  for (int a = 0; a < 3; ++a) {
    const std::int64_t o = origin[a], e = end[a];
    const std::int64_t lo = e < o ? e - past : e == o ? o - past : o;
    const std::int64_t hi = e > o ? e + past : e == o ? o + past : o;
    if (hi < clip.lo[a] || lo > clip.hi[a]) return RayClip::outside;
    inside = inside && lo >= clip.lo[a] && hi <= clip.hi[a];
  }
  return inside ? RayClip::inside : RayClip::crossing;
}

/// end_point_clear() for a collected ray: its walk ends on its end voxel, never past it.
template <class Key>
bool end_clear(const ScanOrigin& o, const RayEnd& r, double inv_resolution) {
  const double length = octomap_norm(r.end.x - o.point.x, r.end.y - o.point.y, r.end.z - o.point.z);
  const double margin = end_margin(length * inv_resolution);
  const float e[3] = {r.end.x, r.end.y, r.end.z};
  for (int a = 0; a < 3; ++a) {
    const double f = inv_resolution * static_cast<double>(e[a]) -
                     static_cast<double>(r.key[a] - static_cast<std::int32_t>(Key::center));
    if (!(f > margin && f < 1.0 - margin)) return false;
  }
  return true;
}

/// Whether a box's edges are whole bricks (a tile's are).
inline bool brick_aligned(const KeyBox& b) {
  constexpr std::int64_t m = kBrickEdge - 1;
  for (int a = 0; a < 3; ++a)
    if ((b.lo[a] & m) != 0 || ((b.hi[a] + 1) & m) != 0) return false;
  return true;
}

/// Restricts one thread's collected part to `clip`: the hits inside it (with their log-odds, in
/// point order). When the scan's origin lies inside a clip of whole bricks every ray is kept and
/// walked whole, the scan as fast as unclipped (the apply then leaves out the bricks outside the
/// clip). Otherwise the rays that cannot reach the clip are dropped, those that cannot leave it
/// kept, and the rest appended to `crossing`: each is walked alone from its first voxel inside the
/// clip (jump_to_entry). The part's key box and steps are those of what it keeps.
template <class Key>
void clip_part(ScanPart& part, const ScanOrigin& o, const KeyBox& clip,
               std::vector<RayEnd>& crossing, double inv_resolution) {
  std::size_t kept = 0;
  const bool rated = !part.hit_logodds.empty();
  KeyBox box = KeyBox::empty<Key>();
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
  const std::int64_t origin[3] = {o.key[0], o.key[1], o.key[2]};
  if (o.in_range && box_contains(clip, origin) && brick_aligned(clip))
    return;  // the whole scan, its box as collected

  // A crossing ray of a clip of whole bricks is walked on from its entry voxel to its end (the
  // apply leaves out the bricks past the clip): its box runs from the clip to its end voxel.
  const bool whole_rest = brick_aligned(clip);
  std::size_t steps = 0;
  kept = 0;
  RayEnd* rays = part.rays.data();
  for (std::size_t i = 0; i < part.rays.size(); ++i) {
    const RayEnd& r = rays[i];
    const RayClip c =
        classify_ray(o.key, r.key, clip, end_clear<Key>(o, r, inv_resolution) ? 0 : 1);
    if (c == RayClip::outside) continue;
    std::int64_t lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      const std::int64_t e = r.key[a];
      lo[a] = std::max<std::int64_t>(std::min<std::int64_t>(o.key[a], e) - 1,
                                     whole_rest ? std::min(clip.lo[a], e - 1) : clip.lo[a]);
      hi[a] = std::min<std::int64_t>(std::max<std::int64_t>(o.key[a], e) + 1,
                                     whole_rest ? std::max(clip.hi[a], e + 1) : clip.hi[a]);
      lo[a] = std::max<std::int64_t>(lo[a], 0);
      hi[a] = std::min<std::int64_t>(hi[a], Key::extent - 1);
      steps += static_cast<std::size_t>(hi[a] - lo[a]);
    }
    box.extend(lo);
    box.extend(hi);
    if (c == RayClip::crossing)
      crossing.push_back(r);
    else
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

/// Where a walk that starts outside a box first enters it.
enum class Entry {
  walk,    ///< walk from the origin (it starts inside, or the entry is at its very end)
  jumped,  ///< the state and position were moved to the first voxel inside
  never,   ///< the walk ends before it enters
};

/// Moves a walk standing on its origin voxel (`s`, `at`) to its first voxel inside `clip`, with
/// the state walk_ray() would have there, without walking the voxels before it.
///
/// walk_ray() steps, each time, the axis with the smallest t_max (the higher axis on ties), and
/// an axis' t_max after j of its steps is its start value plus t_delta added j times, in order,
/// in double. So the walk is the merge of three sequences of step events ordered by
/// (t, higher axis first). The walk enters the box at the latest of the axes' entering events;
/// at that event each other axis has taken exactly its events that come before it in that order,
/// which its own sequence alone tells. The sums are the walk's own, added in the same order, so
/// the state is bit for bit the walked one. Where the end voxel's countdown could matter (the
/// entry is at or past as many steps as the ray has), Entry::walk leaves the walk to walk_ray.
inline Entry jump_to_entry(WalkState& s, KeyPosition& at, const KeyBox& clip) {
  std::int64_t first[3], last[3];  // steps of each axis at which it is inside the box
  bool inside = true;
  for (int a = 0; a < 3; ++a) {
    const std::int64_t k = at.k[a], d = at.dir[a];
    if (k >= clip.lo[a] && k <= clip.hi[a]) {
      first[a] = 0;
      last[a] = d > 0   ? clip.hi[a] - k
                : d < 0 ? k - clip.lo[a]
                        : std::numeric_limits<std::int64_t>::max();
      continue;
    }
    inside = false;
    if (d > 0 && k < clip.lo[a]) {
      first[a] = clip.lo[a] - k;
      last[a] = clip.hi[a] - k;
    } else if (d < 0 && k > clip.hi[a]) {
      first[a] = k - clip.hi[a];
      last[a] = k - clip.lo[a];
    } else {
      return Entry::never;  // moving away, or not moving, outside the box on this axis
    }
  }
  if (inside) return Entry::walk;
  // The entering event of each axis that starts outside: its first[a]-th step, at the t_max it
  // had after first[a] - 1 steps; the walk enters at the latest of them.
  double t[3];
  int entry = -1;
  double when = 0.0;
  for (int a = 0; a < 3; ++a) {
    t[a] = s.t_max[a];
    if (first[a] == 0) continue;
    for (std::int64_t j = 1; j < first[a]; ++j) t[a] += s.t_delta[a];
    if (entry < 0 || t[a] > when || (t[a] == when && a < entry)) {
      entry = a;
      when = t[a];
    }
  }
  if (!(when <= s.length)) return Entry::never;  // the walk ends before that event
  // Every other axis: the steps whose event comes before the entering one.
  std::int64_t steps = 0, n[3];
  for (int a = 0; a < 3; ++a) {
    if (a == entry) {
      n[a] = first[a];
      t[a] += s.t_delta[a];
    } else {
      if (first[a] > 0) {  // t[a] holds its value after first[a] - 1 steps: continue from there
        n[a] = first[a] - 1;
      } else {
        n[a] = 0;
        t[a] = s.t_max[a];
      }
      while (t[a] < when || (t[a] == when && a > entry)) {
        t[a] += s.t_delta[a];
        ++n[a];
      }
      if (n[a] > last[a]) return Entry::never;  // this axis has left the box already
    }
    steps += n[a];
  }
  if (steps >= s.steps_to_end) {
    // The countdown reaches the end voxel's step first (or at the entry): standing on the end
    // voxel then ends the walk before it marks anything inside; otherwise (rounding carried it past
    // the end voxel) the walk is left to walk_ray.
    bool at_end = steps == s.steps_to_end;
    for (int a = 0; a < 3 && at_end; ++a) at_end = at.k[a] + at.dir[a] * n[a] == at.end[a];
    return at_end ? Entry::never : Entry::walk;
  }
  for (int a = 0; a < 3; ++a) {
    at.k[a] += at.dir[a] * n[a];
    s.t_max[a] = t[a];
  }
  s.steps_to_end -= steps;
  if (std::min(std::min(t[0], t[1]), t[2]) > s.length) return Entry::never;  // the entry ends it
  return Entry::jumped;
}

/// A crossing ray's walk from its origin voxel (already set up in `at`, `state`); returns the
/// voxels marked.
template <class Key, class Mark>
std::size_t walk_clipped(const WalkState& state, KeyPosition at, const KeyBox& clip, Mark& mark) {
  CrossingVisit<Key, Mark> visit{clip, mark};
  WalkState s = state;
  switch (jump_to_entry(s, at, clip)) {
    case Entry::never:
      return 0;
    case Entry::jumped:  // the first voxel inside, then the walk from there
      if (visit(at)) walk_ray(s, at, visit);
      return visit.visits;
    case Entry::walk:
      break;
  }
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
