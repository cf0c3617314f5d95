// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A 2D occupancy grid for navigation (what ROS map_server and Nav2 load), projected from a
// height band of a 3D map.
//
// The plane is spanned by two of the map's axes and "up" is the third, each with a sign
// (PlaneFrame: right, forward, up; right-handed). A cell is one column of voxels; the band holds
// the voxels whose centre's height (the up coordinate) lies in [band_min, band_max]. A cell is
//   occupied  when any known voxel of its column in the band is occupied,
//   free      when its column has known voxels in the band and all of them are free,
//   unknown   otherwise.
// The grid covers the box of the band's known voxels. Cells are stored as nav_msgs/OccupancyGrid
// stores them: row-major from the cell at the origin, x (right) fastest, y (forward) growing
// with the row; values 100 occupied, 0 free, -1 unknown.

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "../core/config.hpp"
#include "occupancy_map.hpp"

namespace knnocc {

/// Right, forward and up as signed map axes: display coordinate i of a map point p is
/// sign[i] * p[axis[i]].
struct PlaneFrame {
  std::array<int, 3> axis{0, 1, 2};
  std::array<int, 3> sign{1, 1, 1};

  /// The frame whose up is map axis `up_axis` (0, 1, 2) with sign `up_sign` (+1, -1): right is x
  /// (y when x is up), forward = up x right.
  static PlaneFrame with_up(int up_axis, int up_sign) {
    PlaneFrame f;
    f.axis[2] = up_axis;
    f.sign[2] = up_sign;
    f.axis[0] = up_axis == 0 ? 1 : 0;
    f.sign[0] = 1;
    // e_a x e_b = +e_c for cyclic (a, b, c), -e_c otherwise.
    const int a = up_axis, b = f.axis[0];
    f.axis[1] = 3 - a - b;
    f.sign[1] = up_sign * (((b - a + 3) % 3 == 1) ? 1 : -1);
    return f;
  }
};

struct OccupancyGrid2D {
  static constexpr std::int8_t kOccupied = 100, kFree = 0, kUnknown = -1;

  double resolution = 0.0;
  double origin[2] = {0.0, 0.0};  ///< plane coordinates (m) of the outer corner of cell (0, 0)
  std::size_t width = 0, height = 0;
  std::vector<std::int8_t> cells;  ///< width * height, cell (x, y) at x + y * width

  std::int8_t at(std::size_t x, std::size_t y) const { return cells[x + y * width]; }
  bool empty() const { return cells.empty(); }
};

namespace detail {

// Plane index of a finest voxel along one display axis: the voxel spans [j r, (j + 1) r] in
// display coordinates.
template <class Key>
std::int64_t plane_index(const Key& k, int axis, int sign) {
  const std::int64_t i = static_cast<std::int64_t>(k[axis]) - Key::center;
  return sign > 0 ? i : -i - 1;
}

}  // namespace detail

/// The grid of `map`'s voxels whose centre height (along `frame`'s up) lies in
/// [band_min, band_max]; empty when none does. More than `max_cells` cells is a caller error
/// (std::invalid_argument naming the size).
template <class Key>
OccupancyGrid2D project_height_band(const OccupancyMap<Key>& map, const PlaneFrame& frame,
                                    double band_min, double band_max,
                                    std::uint64_t max_cells = std::uint64_t{1} << 30) {
  const double r = map.resolution();
  const auto in_band = [&](const Key& k) {
    const double c = (static_cast<double>(k[frame.axis[2]]) - Key::center + 0.5) * r;
    const double h = frame.sign[2] > 0 ? c : -c;
    return h >= band_min && h <= band_max;
  };
  std::int64_t lo[2] = {std::numeric_limits<std::int64_t>::max(),
                        std::numeric_limits<std::int64_t>::max()};
  std::int64_t hi[2] = {std::numeric_limits<std::int64_t>::min(),
                        std::numeric_limits<std::int64_t>::min()};
  map.for_each_voxel([&](const Key& k, float) {
    if (!in_band(k)) return;
    for (int a = 0; a < 2; ++a) {
      const std::int64_t j = detail::plane_index(k, frame.axis[a], frame.sign[a]);
      lo[a] = std::min(lo[a], j);
      hi[a] = std::max(hi[a], j);
    }
  });
  OccupancyGrid2D grid;
  grid.resolution = r;
  if (lo[0] > hi[0]) return grid;
  const auto w = static_cast<std::uint64_t>(hi[0] - lo[0] + 1);
  const auto h = static_cast<std::uint64_t>(hi[1] - lo[1] + 1);
  if (w > max_cells / h)
    detail::invalid_argument("the 2D grid of the height band would have " + std::to_string(w) +
                             " x " + std::to_string(h) + " cells, more than " +
                             std::to_string(max_cells));
  grid.width = static_cast<std::size_t>(w);
  grid.height = static_cast<std::size_t>(h);
  grid.origin[0] = static_cast<double>(lo[0]) * r;
  grid.origin[1] = static_cast<double>(lo[1]) * r;
  grid.cells.assign(grid.width * grid.height, OccupancyGrid2D::kUnknown);
  map.for_each_voxel([&](const Key& k, float v) {
    if (!in_band(k)) return;
    const auto x =
        static_cast<std::size_t>(detail::plane_index(k, frame.axis[0], frame.sign[0]) - lo[0]);
    const auto y =
        static_cast<std::size_t>(detail::plane_index(k, frame.axis[1], frame.sign[1]) - lo[1]);
    std::int8_t& cell = grid.cells[x + y * grid.width];
    if (map.is_occupied(v))
      cell = OccupancyGrid2D::kOccupied;
    else if (cell == OccupancyGrid2D::kUnknown)
      cell = OccupancyGrid2D::kFree;
  });
  return grid;
}

}  // namespace knnocc
