// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Map-versus-reference metrics of the paper's Table 1 (section 4.2), on finest-level voxels
// ("nodes"), plus precision/recall-style figures and free voxels inside the solids.
//
//   shell              voxels on the reference's surface: the voxel (closed box) meets a solid's
//                      surface and lies inside no solid (Reference::relation == boundary), with
//                      its centre above the ground (faces resting on the ground are not seen)
//   in_shell           occupied voxels that are shell voxels        ("nodes in reference shell")
//   covered            occupied voxels on the shell or inside it     ("nodes covered by reference")
//   irrelevant         occupied voxels whose centre is farther than `inflate` (0.3 m) from every
//                      solid, ignoring the ground band: centres less than `ground_band` (0.3 m)
//                      above the ground, and everything below it    ("irrelevant nodes")
//   evaluated          occupied voxels outside the ground band (irrelevant's population)
//   precision          1 - irrelevant / evaluated
//   shell_recall       in_shell / shell
//   free_inside        free voxels lying entirely inside a solid (space wrongly carved)
//   ground             occupied voxels that meet the ground plane farther than `inflate` from
//                      every solid: the ground the band hides from irrelevant (a sparse textured
//                      ground is real structure a model may lose; Table 1 does not see it)

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "../map/occupancy_map.hpp"
#include "reference.hpp"

namespace knnocc::eval {

/// Default for the most voxels count_shell() examines (the reference's bounding box in voxels): a
/// box larger than this (e.g. a kilometre-sized shape at centimetre voxels) is refused as a
/// mistake.
inline constexpr std::uint64_t kMaxShellBox = std::uint64_t{1} << 31;

struct MetricOptions {
  double inflate = 0.3;      ///< reference inflation for irrelevant nodes (m)
  double ground_band = 0.3;  ///< ignored height above the ground for irrelevant nodes (m)
  /// Largest reference bounding box (in voxels) the shell count walks; its time grows with the
  /// box, so a harness with a time budget (the fuzzer) sets it lower.
  std::uint64_t max_shell_box = kMaxShellBox;
};

struct Metrics {
  std::size_t occupied = 0, free = 0;  ///< finest-level voxels of the map
  std::size_t shell = 0;               ///< voxels of the reference shell at the map's resolution
  std::size_t in_shell = 0, covered = 0, irrelevant = 0, evaluated = 0, free_inside = 0;
  std::size_t ground = 0;  ///< occupied voxels on the ground, away from the solids

  double precision() const {
    return evaluated ? 1.0 - static_cast<double>(irrelevant) / static_cast<double>(evaluated) : 1.0;
  }
  double shell_recall() const {
    return shell ? static_cast<double>(in_shell) / static_cast<double>(shell) : 0.0;
  }
};

/// How the voxel centred at c (edge r) lies relative to the reference.
inline BoxRelation voxel_relation(const Reference& ref, const Point3d& c, double r) {
  return ref.relation({c.x - r / 2, c.y - r / 2, c.z - r / 2},
                      {c.x + r / 2, c.y + r / 2, c.z + r / 2});
}
/// Shell voxel: on a surface, centre above the ground.
inline bool on_shell(const Reference& ref, BoxRelation rel, const Point3d& c) {
  return rel == BoxRelation::boundary && !(ref.has_ground && !(c.z > ref.ground_z));
}

/// Voxels of the grid that lie on the reference's shell. Only voxels inside the key range are
/// counted (a map cannot hold others); a bounding box of more than `max_box` voxels is
/// std::invalid_argument.
template <class Key>
std::size_t count_shell(const Grid<Key>& grid, const Reference& ref,
                        std::uint64_t max_box = kMaxShellBox) {
  Point3d lo, hi;
  ref.bounds(grid.resolution(), lo, hi);
  if (!(lo.x <= hi.x)) return 0;
  const double r = grid.resolution();
  // Key-space box in 64 bits, clamped to the key range (no wrap-around of narrow key types).
  std::int64_t klo[3], khi[3];
  const double l[3] = {lo.x, lo.y, lo.z}, h[3] = {hi.x, hi.y, hi.z};
  std::uint64_t box = 1;
  for (int a = 0; a < 3; ++a) {
    const double c = static_cast<double>(Key::center), top = static_cast<double>(Key::extent - 1);
    klo[a] = static_cast<std::int64_t>(std::min(std::max(std::floor(l[a] / r) + c, 0.0), top));
    khi[a] = static_cast<std::int64_t>(std::min(std::max(std::floor(h[a] / r) + c, 0.0), top));
    box *= static_cast<std::uint64_t>(khi[a] - klo[a] + 1);
    if (box > max_box)
      knnocc::detail::invalid_argument("the reference's bounding box spans more than " +
                                       std::to_string(max_box) + " voxels at " + std::to_string(r) +
                                       " m");
  }
  std::size_t n = 0;
  for (std::int64_t x = klo[0]; x <= khi[0]; ++x)
    for (std::int64_t y = klo[1]; y <= khi[1]; ++y)
      for (std::int64_t z = klo[2]; z <= khi[2]; ++z) {
        const Point3d c{grid.index_to_coord(static_cast<typename Key::index_type>(x)),
                        grid.index_to_coord(static_cast<typename Key::index_type>(y)),
                        grid.index_to_coord(static_cast<typename Key::index_type>(z))};
        n += on_shell(ref, voxel_relation(ref, c, r), c);
      }
  return n;
}

/// Table 1 and the rest for a map (occupied: the map's occupancy threshold).
template <class Key>
Metrics evaluate(const OccupancyMap<Key>& map, const Reference& ref, MetricOptions opt = {}) {
  Metrics m;
  const Grid<Key>& g = map.grid();
  const double r = g.resolution();
  m.shell = count_shell(g, ref, opt.max_shell_box);
  map.for_each_voxel([&](const Key& k, float v) {
    const Point3d c{g.index_to_coord(k[0]), g.index_to_coord(k[1]), g.index_to_coord(k[2])};
    const BoxRelation rel = voxel_relation(ref, c, r);
    if (!map.is_occupied(v)) {
      ++m.free;
      m.free_inside += rel == BoxRelation::inside;
      return;
    }
    ++m.occupied;
    const bool shell = on_shell(ref, rel, c);
    m.in_shell += shell;
    m.covered += shell || rel == BoxRelation::inside;
    if (ref.has_ground && c.z - r / 2 <= ref.ground_z && ref.ground_z < c.z + r / 2 &&
        ref.distance(c) > opt.inflate)
      ++m.ground;
    if (ref.has_ground && c.z - ref.ground_z < opt.ground_band) return;  // the ground band
    ++m.evaluated;
    m.irrelevant += ref.distance(c) > opt.inflate;
  });
  return m;
}

}  // namespace knnocc::eval
