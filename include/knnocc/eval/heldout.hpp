// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Held-out evaluation: map quality on real keyframes without ground truth and without any rule of
// the model under test. The keyframes are split into F interleaved folds (fold f: the keyframes
// i with i % F == f); for each fold a map is built from the other folds' keyframes and scored
// against the fold's own, which the map has not seen:
//
//   points        held-out map points (ids) that at least min_views (2) held-out keyframes
//                 observe: structure that several independent views agree on
//   recalled      of those, the ones whose voxel (at the point's world position, the first
//                 held-out observation's) is occupied in the map       recall = recalled / points
//   rays          the held-out keyframes' rays (sensor -> point) to those points
//   seen_through  distinct occupied voxels of the map that such a ray passes through before its
//                 end voxel (the voxels the held-out keyframe saw empty: a contradiction of the
//                 map by data it was not built from); the origin voxel counts, the end voxel not
//   seen_both     of those, the ones holding a scored point: voxels the held-out keyframes saw
//                 both empty and occupied (as at a depth edge), against the map only in part;
//                 the others the held-out keyframes saw only empty (seen_empty_only())
//   occupied      occupied voxels of the map (seen_through is a share of it)
// Scores are summed over the folds (each fold's map counts its own voxels). Only rays to
// multi-view points are walked: the ray of a wrong match seen once ends off the surface and
// would pass through correct structure.
//
// The floor (HeldoutFloor) is what no map can beat on the same keyframes: the fewest seen-through
// voxels of any maps with a given recall. A held-out point may lie in a voxel that another held-out
// ray crosses (a depth edge, a grazing ray, depth noise); a map that recalls it contradicts that
// ray. The floor tells how much of a seen-through count the resolution and the data impose.
//
// The maps come from a caller's function build(train) -> OccupancyMap (train: the indices of the
// keyframes to map, in sequence order), so the evaluation knows nothing of models or Mapper.
//
// Thread safety: functions of their arguments only.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "../core/config.hpp"
#include "../core/key.hpp"
#include "../core/point3.hpp"
#include "../core/point_evidence.hpp"
#include "../core/point_traits.hpp"
#include "../map/occupancy_map.hpp"
#include "../raycast/dda.hpp"

namespace knnocc::eval {

/// One keyframe: its sensor position and its points in the world frame, one map-point id each.
struct IdKeyframe {
  Point3d origin;
  std::vector<Point3d> points;
  std::vector<std::uint64_t> ids;
  std::vector<PointEvidence> evidence;  ///< the SLAM counters, one per point, or empty
};

struct HeldoutOptions {
  std::size_t folds = 5;        ///< interleaved folds (>= 2)
  std::uint32_t min_views = 2;  ///< held-out keyframes that must observe a scored map point
  /// The walk stops this far (m) before the point: 0 walks the whole ray up to the end voxel.
  double end_margin = 0.0;
};

struct HeldoutScore {
  std::size_t points = 0, recalled = 0, rays = 0, seen_through = 0, seen_both = 0, occupied = 0;

  double recall() const { return points ? double(recalled) / double(points) : 0.0; }
  /// seen_through as a share of the occupied voxels.
  double seen_through_share() const {
    return occupied ? double(seen_through) / double(occupied) : 0.0;
  }
  /// The seen-through voxels the held-out keyframes saw only empty.
  std::size_t seen_empty_only() const { return seen_through - seen_both; }
  HeldoutScore& operator+=(const HeldoutScore& o) {
    points += o.points;
    recalled += o.recalled;
    rays += o.rays;
    seen_through += o.seen_through;
    seen_both += o.seen_both;
    occupied += o.occupied;
    return *this;
  }
};

/// The indices of fold f's keyframes (held_out) or of all the others, in sequence order.
inline std::vector<std::size_t> fold_indices(std::size_t keyframes, std::size_t folds,
                                             std::size_t f, bool held_out) {
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < keyframes; ++i)
    if ((i % folds == f) == held_out) out.push_back(i);
  return out;
}

/// Where each held-out map point was first observed and by how many of the held-out keyframes
/// (an id counts once per keyframe).
struct HeldoutPoint {
  Point3d position;
  std::uint32_t views = 0;
  std::size_t last = static_cast<std::size_t>(-1);  // keyframe that counted it last
};
using HeldoutPoints = std::unordered_map<std::uint64_t, HeldoutPoint>;

/// The map points of keyframes[heldout] and their views.
inline HeldoutPoints heldout_points(const std::vector<IdKeyframe>& keyframes,
                                    const std::vector<std::size_t>& heldout) {
  HeldoutPoints seen;
  for (const std::size_t i : heldout) {
    const IdKeyframe& kf = keyframes[i];
    for (std::size_t j = 0; j < kf.points.size() && j < kf.ids.size(); ++j) {
      auto [it, fresh] = seen.try_emplace(kf.ids[j]);
      if (fresh) it->second.position = kf.points[j];
      if (it->second.last != i) ++it->second.views;  // an id counts once per keyframe
      it->second.last = i;
    }
  }
  return seen;
}

/// The voxels of the points `points` says min_views held-out keyframes observe, with how many
/// each holds; `scored` receives the number of such points, in the grid or not.
template <class Key>
std::unordered_map<Key, std::size_t, KeyHash> scored_voxels(const Grid<Key>& g,
                                                            const HeldoutPoints& points,
                                                            const HeldoutOptions& opt,
                                                            std::size_t& scored) {
  std::unordered_map<Key, std::size_t, KeyHash> voxels;
  scored = 0;
  for (const auto& e : points) {
    if (e.second.views < opt.min_views) continue;
    ++scored;
    Key k;
    if (g.point_to_key(e.second.position, k)) ++voxels[k];
  }
  return voxels;
}

/// Walks the rays the score walks (held-out keyframe i's ray to its point j, for points `points`
/// says min_views held-out keyframes observe, stopped end_margin short) and calls f(i, j, key) for
/// every voxel of `grid` each passes before its end voxel; returns the rays walked.
template <class Key, class F>
std::size_t for_each_heldout_ray_key(const Grid<Key>& g, const std::vector<IdKeyframe>& keyframes,
                                     const std::vector<std::size_t>& heldout,
                                     const HeldoutPoints& points, const HeldoutOptions& opt,
                                     F&& f) {
  std::size_t rays = 0;
  for (const std::size_t i : heldout) {
    const IdKeyframe& kf = keyframes[i];
    const Point3f o = knnocc::detail::to_point3f(kf.origin);
    for (std::size_t j = 0; j < kf.points.size() && j < kf.ids.size(); ++j) {
      if (points.at(kf.ids[j]).views < opt.min_views) continue;
      ++rays;
      Point3d end = kf.points[j];
      if (opt.end_margin > 0) {
        const double dx = end.x - kf.origin.x, dy = end.y - kf.origin.y, dz = end.z - kf.origin.z;
        const double len = std::sqrt(dx * dx + dy * dy + dz * dz);
        if (len <= opt.end_margin) continue;
        const double s = (len - opt.end_margin) / len;
        end = {kf.origin.x + s * dx, kf.origin.y + s * dy, kf.origin.z + s * dz};
      }
      for_each_ray_key(g, o, knnocc::detail::to_point3f(end), [&](const Key& k) { f(i, j, k); });
    }
  }
  return rays;
}

/// for_each_heldout_ray_key restricted to the occupied voxels of `map`.
template <class Key, class F>
std::size_t for_each_seen_through(const OccupancyMap<Key>& map,
                                  const std::vector<IdKeyframe>& keyframes,
                                  const std::vector<std::size_t>& heldout,
                                  const HeldoutPoints& points, const HeldoutOptions& opt, F&& f) {
  return for_each_heldout_ray_key(map.grid(), keyframes, heldout, points, opt,
                                  [&](std::size_t i, std::size_t j, const Key& k) {
                                    if (map.is_occupied(k).value_or(false)) f(i, j, k);
                                  });
}

/// Scores `map` against the held-out keyframes `heldout` (indices into `keyframes`);
/// `seen_through` (optional) receives the seen-through voxels.
template <class Key>
HeldoutScore score_heldout(const OccupancyMap<Key>& map, const std::vector<IdKeyframe>& keyframes,
                           const std::vector<std::size_t>& heldout, const HeldoutOptions& opt = {},
                           std::vector<Key>* seen_through = nullptr) {
  const HeldoutPoints seen = heldout_points(keyframes, heldout);
  HeldoutScore s;
  const auto scored = scored_voxels(map.grid(), seen, opt, s.points);
  for (const auto& [k, n] : scored)
    if (map.is_occupied(k).value_or(false)) s.recalled += n;
  std::unordered_set<Key, KeyHash> through;
  s.rays =
      for_each_seen_through(map, keyframes, heldout, seen, opt,
                            [&](std::size_t, std::size_t, const Key& k) { through.insert(k); });
  s.seen_through = through.size();
  for (const Key& k : through) s.seen_both += scored.count(k);
  if (seen_through) seen_through->assign(through.begin(), through.end());
  s.occupied = map.count_voxels().occupied;
  return s;
}

namespace detail {
inline void check_folds(const HeldoutOptions& opt, std::size_t keyframes) {
  if (opt.folds < 2 || opt.folds > keyframes)
    knnocc::detail::invalid_argument("held-out evaluation: folds must be in [2, keyframes]");
}
}  // namespace detail

/// All folds: build(train) (train: the other folds' keyframe indices, in order) returns the map
/// of those keyframes, scored against the fold under each of `opts` (one map per fold for all of
/// them); one score per option. folds < 2, more folds than keyframes, or options that differ in
/// folds: std::invalid_argument.
template <class Build>
std::vector<HeldoutScore> evaluate_heldout(const std::vector<IdKeyframe>& keyframes,
                                           const std::vector<HeldoutOptions>& opts, Build&& build) {
  std::vector<HeldoutScore> total(opts.size());
  if (opts.empty()) return total;
  const std::size_t folds = opts[0].folds;
  detail::check_folds(opts[0], keyframes.size());
  for (const HeldoutOptions& o : opts)
    if (o.folds != folds)
      knnocc::detail::invalid_argument(
          "held-out evaluation: every option must have the same folds");
  for (std::size_t f = 0; f < folds; ++f) {
    const auto map = build(fold_indices(keyframes.size(), folds, f, false));
    const auto held = fold_indices(keyframes.size(), folds, f, true);
    for (std::size_t o = 0; o < opts.size(); ++o)
      total[o] += score_heldout(map, keyframes, held, opts[o]);
  }
  return total;
}

/// The same under one option.
template <class Build>
HeldoutScore evaluate_heldout(const std::vector<IdKeyframe>& keyframes, const HeldoutOptions& opt,
                              Build&& build) {
  return evaluate_heldout(keyframes, std::vector<HeldoutOptions>{opt}, build).front();
}

/// What no map can beat on the same held-out keyframes: a scored point is recalled only through
/// its voxel, and a voxel that one of its fold's held-out rays passes before the end voxel
/// (crossed) is a seen-through voxel whenever that fold's map occupies it. Maps that occupy every
/// uncrossed voxel holding scored points, and of the crossed ones those holding the most points
/// first, recall the most for the fewest seen-through voxels; fewest_seen_through is that least
/// count, exact for the folds' maps together (voxels holding no scored point add no recall).
struct HeldoutFloor {
  std::size_t points = 0;     ///< scored points, as HeldoutScore::points
  std::size_t uncrossed = 0;  ///< of them, in voxels that no held-out ray of their fold crosses
  std::vector<std::size_t> crossed;  ///< scored points in each crossed voxel (of each fold)

  /// The fewest seen-through voxels of maps that recall `recalled` points; nullopt if no map
  /// can (points outside the grid are never recalled).
  std::optional<std::size_t> fewest_seen_through(std::size_t recalled) const {
    std::vector<std::size_t> most = crossed;
    std::sort(most.begin(), most.end(), std::greater<>());
    std::size_t have = uncrossed, voxels = 0;
    for (const std::size_t n : most) {
      if (have >= recalled) break;
      have += n;
      ++voxels;
    }
    if (have < recalled) return std::nullopt;
    return voxels;
  }
  HeldoutFloor& operator+=(const HeldoutFloor& o) {
    points += o.points;
    uncrossed += o.uncrossed;
    crossed.insert(crossed.end(), o.crossed.begin(), o.crossed.end());
    return *this;
  }
};

/// The floor of one fold: keyframes[heldout] against any map on `grid`.
template <class Key>
HeldoutFloor heldout_floor(const Grid<Key>& grid, const std::vector<IdKeyframe>& keyframes,
                           const std::vector<std::size_t>& heldout,
                           const HeldoutOptions& opt = {}) {
  const HeldoutPoints seen = heldout_points(keyframes, heldout);
  HeldoutFloor floor;
  const auto in_voxel = scored_voxels(grid, seen, opt, floor.points);
  std::unordered_set<Key, KeyHash> crossed;
  for_each_heldout_ray_key(grid, keyframes, heldout, seen, opt,
                           [&](std::size_t, std::size_t, const Key& k) {
                             if (in_voxel.count(k)) crossed.insert(k);
                           });
  for (const auto& [k, n] : in_voxel) {
    if (crossed.count(k))
      floor.crossed.push_back(n);
    else
      floor.uncrossed += n;
  }
  return floor;
}

/// The floor of all folds (split as evaluate_heldout splits them).
template <class Key>
HeldoutFloor evaluate_heldout_floor(const Grid<Key>& grid, const std::vector<IdKeyframe>& keyframes,
                                    const HeldoutOptions& opt) {
  detail::check_folds(opt, keyframes.size());
  HeldoutFloor total;
  for (std::size_t f = 0; f < opt.folds; ++f)
    total +=
        heldout_floor(grid, keyframes, fold_indices(keyframes.size(), opt.folds, f, true), opt);
  return total;
}

}  // namespace knnocc::eval
