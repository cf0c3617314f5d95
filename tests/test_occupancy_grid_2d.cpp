// project_height_band (map/occupancy_grid_2d.hpp): the 2D grid of a height band against a brute
// force over voxel centres, for every up direction.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <utility>

#include <knnocc/map/occupancy_grid_2d.hpp>

#include "test_support.hpp"

using knnocc::OccupancyGrid2D;
using knnocc::OccupancyMap;
using knnocc::OcKey;
using knnocc::PlaneFrame;

namespace {

OccupancyMap<OcKey> random_map(std::uint64_t seed) {
  OccupancyMap<OcKey> map(0.1);
  knnocc::test::Rng rng(seed);
  std::uniform_int_distribution<int> k(32768 - 20, 32768 + 20);
  std::uniform_real_distribution<float> v(-2.0f, 3.5f);
  for (int i = 0; i < 4000; ++i)
    map.set(OcKey(static_cast<std::uint16_t>(k(rng)), static_cast<std::uint16_t>(k(rng)),
                  static_cast<std::uint16_t>(k(rng))),
            v(rng));
  return map;
}

}  // namespace

TEST_CASE("occupancy_grid_2d.PlaneFrame::with_up is right-handed for every up direction") {
  for (int axis = 0; axis < 3; ++axis)
    for (int sign : {1, -1}) {
      const PlaneFrame f = PlaneFrame::with_up(axis, sign);
      // e_right x e_forward must be e_up: the determinant of the signed permutation is +1.
      int m[3][3] = {};
      for (int i = 0; i < 3; ++i) m[i][f.axis[i]] = f.sign[i];
      const int det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                      m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                      m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
      CHECK(det == 1);
      CHECK(f.axis[2] == axis);
      CHECK(f.sign[2] == sign);
    }
  // ORB-SLAM's world (the first camera: y down, z forward): up -y gives right x, forward z.
  const PlaneFrame cam = PlaneFrame::with_up(1, -1);
  CHECK(cam.axis == std::array<int, 3>{0, 2, 1});
  CHECK(cam.sign == std::array<int, 3>{1, 1, -1});
}

TEST_CASE("occupancy_grid_2d.cells equal a brute force over the band's voxel centres") {
  const OccupancyMap<OcKey> map = random_map(4);
  const double r = map.resolution();
  for (int axis = 0; axis < 3; ++axis)
    for (int sign : {1, -1}) {
      CAPTURE(axis);
      CAPTURE(sign);
      const PlaneFrame f = PlaneFrame::with_up(axis, sign);
      const double lo = -0.7, hi = 0.45;
      const OccupancyGrid2D g = knnocc::project_height_band(map, f, lo, hi);
      REQUIRE_FALSE(g.empty());
      CHECK(g.cells.size() == g.width * g.height);
      // Per cell (from voxel centres in display coordinates): any occupied, any known.
      std::map<std::pair<long, long>, std::pair<bool, bool>> truth;
      long min_x = 1L << 40, min_y = 1L << 40, max_x = -(1L << 40), max_y = -(1L << 40);
      map.for_each_voxel([&](const OcKey& k, float v) {
        double c[3];
        for (int a = 0; a < 3; ++a) c[a] = map.grid().index_to_coord(k[a]);
        const double up = f.sign[2] * c[f.axis[2]];
        if (up < lo || up > hi) return;
        const long x = std::lround(std::floor((f.sign[0] * c[f.axis[0]] - g.origin[0]) / r));
        const long y = std::lround(std::floor((f.sign[1] * c[f.axis[1]] - g.origin[1]) / r));
        auto& t = truth[{x, y}];
        t.first = t.first || map.is_occupied(v);
        t.second = true;
        min_x = std::min(min_x, x), max_x = std::max(max_x, x);
        min_y = std::min(min_y, y), max_y = std::max(max_y, y);
      });
      CHECK(min_x == 0);
      CHECK(min_y == 0);
      CHECK(max_x + 1 == static_cast<long>(g.width));
      CHECK(max_y + 1 == static_cast<long>(g.height));
      std::size_t wrong = 0, occupied = 0, free = 0;
      for (std::size_t y = 0; y < g.height; ++y)
        for (std::size_t x = 0; x < g.width; ++x) {
          const auto it = truth.find({static_cast<long>(x), static_cast<long>(y)});
          const std::int8_t expect = it == truth.end()  ? OccupancyGrid2D::kUnknown
                                     : it->second.first ? OccupancyGrid2D::kOccupied
                                                        : OccupancyGrid2D::kFree;
          wrong += g.at(x, y) != expect;
          occupied += expect == OccupancyGrid2D::kOccupied;
          free += expect == OccupancyGrid2D::kFree;
        }
      CHECK(wrong == 0);
      CHECK(occupied > 50);
      CHECK(free > 50);
    }
}

TEST_CASE("occupancy_grid_2d.the band's edges, an empty band and a refused size") {
  OccupancyMap<OcKey> map(0.5);
  // Up = +z: voxel centres at z = 0.25 (occupied) and z = 1.25 (free), same column.
  map.set(OcKey(32768, 32768, 32768), 1.0f);
  map.set(OcKey(32768, 32768, 32770), -1.0f);
  map.set(OcKey(32770, 32768, 32770), -1.0f);
  const PlaneFrame up_z = PlaneFrame::with_up(2, 1);
  OccupancyGrid2D g = knnocc::project_height_band(map, up_z, 0.25, 1.25);  // both centres
  REQUIRE(g.width == 3);
  REQUIRE(g.height == 1);
  CHECK(g.origin[0] == 0.0);
  CHECK(g.origin[1] == 0.0);
  CHECK(g.at(0, 0) == OccupancyGrid2D::kOccupied);
  CHECK(g.at(1, 0) == OccupancyGrid2D::kUnknown);
  CHECK(g.at(2, 0) == OccupancyGrid2D::kFree);
  g = knnocc::project_height_band(map, up_z, 0.5, 2.0);  // the free voxels only
  REQUIRE(g.width == 3);
  CHECK(g.at(0, 0) == OccupancyGrid2D::kFree);
  CHECK(knnocc::project_height_band(map, up_z, 1.3, 2.0).empty());
  // Up = -z: heights are -z, the occupied voxel's centre at -0.25.
  g = knnocc::project_height_band(map, PlaneFrame::with_up(2, -1), -0.3, -0.2);
  REQUIRE(g.width == 1);
  CHECK(g.at(0, 0) == OccupancyGrid2D::kOccupied);
  // A map spanning the whole key range would need 2^32 cells.
  map.set(OcKey(0, 0, 32768), 1.0f);
  map.set(OcKey(65535, 65535, 32768), 1.0f);
  CHECK_THROWS_AS(knnocc::project_height_band(map, up_z, -1.0, 1.0), std::invalid_argument);
}
