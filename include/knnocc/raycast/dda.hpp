#pragma once
// Exact 3D DDA (Amanatides & Woo) that yields exactly the keys of OctoMap's computeRayKeys:
//   - origin voxel included, end voxel never included, nothing when both share a voxel;
//   - direction, length and normalisation in float, tMax/tDelta in double, as in OctoMap;
//   - on ties the higher axis steps first (z over y over x);
//   - stops at the end key, or once the next voxel border lies beyond the ray length.
// The result is a 6-connected walk. Compile with -ffp-contract=off when FMA instructions are
// enabled (-march=native): fused multiply-adds change the last bit of borders and of the max-range
// end point, and so, rarely, a key.

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "../core/grid.hpp"
#include "../core/point3.hpp"

namespace knnocc {

namespace detail {

/// OctoMap's Vector3::norm(): float squares summed in float, square root in double.
inline double octomap_norm(float dx, float dy, float dz) {
  const float s = dx * dx + dy * dy + dz * dz;
  return std::sqrt(static_cast<double>(s));
}

inline bool finite(const Point3f& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

}  // namespace detail

/// End point of a ray truncated at max_range, with OctoMap's float arithmetic:
/// origin + normalized(end - origin) * float(max_range).
inline Point3f truncate_ray(const Point3f& origin, const Point3f& end, double max_range) {
  float dx = end.x - origin.x, dy = end.y - origin.y, dz = end.z - origin.z;
  const double len = detail::octomap_norm(dx, dy, dz);
  if (len > 0) {
    const auto l = static_cast<float>(len);
    dx /= l;
    dy /= l;
    dz /= l;
  }
  const auto m = static_cast<float>(max_range);
  const float sx = dx * m, sy = dy * m, sz = dz * m;  // separate products: no fused multiply-add
  return Point3f{origin.x + sx, origin.y + sy, origin.z + sz};
}

/// Calls visit(key) for every voxel the segment origin -> end crosses, origin voxel included,
/// end voxel excluded. Returns false, visiting nothing, when origin or end is not finite or out
/// of the key range (OctoMap's computeRayKeys returns false there too).
template <class Key, class Visit>
bool for_each_ray_key(const Grid<Key>& grid, const Point3f& origin, const Point3f& end,
                      Visit&& visit) {
  Key ko, ke;
  if (!grid.point_to_key(origin, ko) || !grid.point_to_key(end, ke)) return false;
  if (ko == ke) return true;
  visit(static_cast<const Key&>(ko));

  const float o[3] = {origin.x, origin.y, origin.z};
  float dir[3] = {end.x - origin.x, end.y - origin.y, end.z - origin.z};
  const auto length = static_cast<float>(detail::octomap_norm(dir[0], dir[1], dir[2]));
  for (float& d : dir) d /= length;

  const double res = grid.resolution();
  int step[3];
  double t_max[3], t_delta[3];
  std::int64_t cur[3], stop[3];
  for (int i = 0; i < 3; ++i) {
    cur[i] = ko[i];
    stop[i] = ke[i];
    step[i] = dir[i] > 0.0f ? 1 : (dir[i] < 0.0f ? -1 : 0);
    if (step[i] != 0) {
      double border = grid.index_to_coord(ko[i]);
      border += static_cast<float>(step[i] * res * 0.5);
      t_max[i] = (border - static_cast<double>(o[i])) / static_cast<double>(dir[i]);
      t_delta[i] = res / static_cast<double>(std::fabs(dir[i]));
    } else {
      t_max[i] = std::numeric_limits<double>::max();
      t_delta[i] = std::numeric_limits<double>::max();
    }
  }

  using I = typename Key::index_type;
  for (;;) {
    const int dim =
        (t_max[0] < t_max[1]) ? (t_max[0] < t_max[2] ? 0 : 2) : (t_max[1] < t_max[2] ? 1 : 2);
    cur[dim] += step[dim];
    t_max[dim] += t_delta[dim];
    if (cur[0] == stop[0] && cur[1] == stop[1] && cur[2] == stop[2]) return true;
    const double dist = std::min(std::min(t_max[0], t_max[1]), t_max[2]);
    if (dist > static_cast<double>(length)) return true;
    // OctoMap only asserts here; a walk that would leave the key range ends instead.
    if (cur[dim] < 0 || cur[dim] >= Key::extent) return true;
    visit(Key(static_cast<I>(cur[0]), static_cast<I>(cur[1]), static_cast<I>(cur[2])));
  }
}

/// The keys of for_each_ray_key in a vector (cleared first). Returns false when out of range.
template <class Key>
bool compute_ray_keys(const Grid<Key>& grid, const Point3f& origin, const Point3f& end,
                      std::vector<Key>& out) {
  out.clear();
  return for_each_ray_key(grid, origin, end, [&](const Key& k) { out.push_back(k); });
}

}  // namespace knnocc
