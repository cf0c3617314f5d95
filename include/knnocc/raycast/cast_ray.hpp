// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// cast_ray: the first occupied voxel along a direction (OctoMap's castRay semantics).
//
// The walk starts in the origin voxel (an occupied origin voxel is a hit at once) and steps with
// the same DDA as compute_ray_keys, in double like OctoMap's castRay. It stops at
//   - an occupied voxel                      -> CastStatus::occupied
//   - an unknown voxel, unless ignore_unknown -> CastStatus::unknown
//   - a voxel centre farther than max_range  -> CastStatus::max_range   (max_range <= 0: no limit)
//   - the edge of the key range              -> CastStatus::out_of_bounds
// `end` is the centre of the voxel where the walk stopped (OctoMap's `end`).

#include <cmath>
#include <limits>

#include "../core/point3.hpp"
#include "../map/occupancy_map.hpp"
#include "dda.hpp"

namespace knnocc {

enum class CastStatus { occupied, unknown, max_range, out_of_bounds, invalid };

template <class Key>
struct CastResult {
  CastStatus status = CastStatus::invalid;
  Key key{};      ///< voxel where the walk stopped (valid unless status is invalid)
  Point3f end{};  ///< centre of that voxel
  bool hit() const { return status == CastStatus::occupied; }
};

template <class Key>
CastResult<Key> cast_ray(const OccupancyMap<Key>& map, const Point3f& origin,
                         const Point3f& direction, bool ignore_unknown = false,
                         double max_range = -1.0) {
  CastResult<Key> r;
  const Grid<Key>& grid = map.grid();
  if (!grid.point_to_key(origin, r.key)) return r;  // invalid: origin NaN or out of range
  auto centre = [&](const Key& k) {
    return Point3f{static_cast<float>(grid.index_to_coord(k[0])),
                   static_cast<float>(grid.index_to_coord(k[1])),
                   static_cast<float>(grid.index_to_coord(k[2]))};
  };
  // Whether the walk ends in r.key: an occupied voxel, or an unknown one when unknown stops it.
  auto stops_here = [&] {
    if (const auto v = map.logodds(r.key)) {
      if (!map.is_occupied(*v)) return false;
      r.status = CastStatus::occupied;
      return true;
    }
    if (ignore_unknown) return false;
    r.status = CastStatus::unknown;
    return true;
  };
  r.end = centre(r.key);
  if (stops_here()) return r;

  float dir[3] = {direction.x, direction.y, direction.z};
  if (!(std::isfinite(dir[0]) && std::isfinite(dir[1]) && std::isfinite(dir[2]))) {
    r.status = CastStatus::invalid;
    return r;
  }
  const double len = detail::octomap_norm(dir[0], dir[1], dir[2]);
  if (len > 0)
    for (float& d : dir) d /= detail::to_float(len);
  const float o[3] = {origin.x, origin.y, origin.z};
  const double res = grid.resolution();
  int step[3];
  double t_max[3], t_delta[3];
  std::int64_t cur[3];
  for (int i = 0; i < 3; ++i) {
    cur[i] = r.key[i];
    step[i] = dir[i] > 0.0f ? 1 : (dir[i] < 0.0f ? -1 : 0);
    if (step[i] != 0) {
      double border = grid.index_to_coord(r.key[i]);
      border += static_cast<double>(step[i] * res * 0.5);  // double here, unlike computeRayKeys
      t_max[i] = (border - static_cast<double>(o[i])) / static_cast<double>(dir[i]);
      t_delta[i] = res / static_cast<double>(std::fabs(dir[i]));
    } else {
      t_max[i] = std::numeric_limits<double>::max();
      t_delta[i] = std::numeric_limits<double>::max();
    }
  }
  if (step[0] == 0 && step[1] == 0 && step[2] == 0) {
    r.status = CastStatus::invalid;  // zero direction
    return r;
  }

  const bool limited = max_range > 0.0;
  const double max_sq = max_range * max_range;
  using I = typename Key::index_type;
  for (;;) {
    const int dim =
        (t_max[0] < t_max[1]) ? (t_max[0] < t_max[2] ? 0 : 2) : (t_max[1] < t_max[2] ? 1 : 2);
    if ((step[dim] < 0 && cur[dim] == 0) || (step[dim] > 0 && cur[dim] == Key::extent - 1)) {
      r.status = CastStatus::out_of_bounds;
      return r;
    }
    cur[dim] += step[dim];
    t_max[dim] += t_delta[dim];
    r.key = Key(static_cast<I>(cur[0]), static_cast<I>(cur[1]), static_cast<I>(cur[2]));
    r.end = centre(r.key);
    if (limited) {
      const float ex = r.end.x - o[0], ey = r.end.y - o[1], ez = r.end.z - o[2];
      double d2 = 0.0;  // OctoMap sums float products into a double
      d2 += static_cast<double>(ex * ex);
      d2 += static_cast<double>(ey * ey);
      d2 += static_cast<double>(ez * ez);
      if (d2 > max_sq) {
        r.status = CastStatus::max_range;
        return r;
      }
    }
    if (stops_here()) return r;
  }
}

}  // namespace knnocc
