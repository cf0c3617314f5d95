// cast_ray (raycast/cast_ray.hpp): the first occupied voxel along a direction.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

#include <knnocc/raycast/cast_ray.hpp>

#include "test_support.hpp"

using knnocc::Grid;
using knnocc::OcKey;
using knnocc::Point3f;

TEST_CASE("cast_ray.first_occupied_voxel") {
  knnocc::OccupancyMap<OcKey> map(0.1);
  const Grid<OcKey>& g = map.grid();
  OcKey wall, free_key, origin_key;
  REQUIRE(g.coord_to_key(1.05, 0.05, 0.05, wall));
  map.update(wall, 2.0f);
  for (int i = 0; i < 10; ++i) {
    REQUIRE(g.coord_to_key(0.05 + 0.1 * i, 0.05, 0.05, free_key));
    map.update(free_key, -1.0f);
  }
  REQUIRE(g.coord_to_key(0.05, 0.05, 0.05, origin_key));

  auto r = knnocc::cast_ray(map, {0.05f, 0.05f, 0.05f}, {1, 0, 0});
  CHECK(r.status == knnocc::CastStatus::occupied);
  CHECK(r.key == wall);
  CHECK(r.end.x == doctest::Approx(1.05));
  SUBCASE("max range stops before the wall") {
    r = knnocc::cast_ray(map, {0.05f, 0.05f, 0.05f}, {1, 0, 0}, false, 0.5);
    CHECK(r.status == knnocc::CastStatus::max_range);
  }
  SUBCASE("unknown voxels stop the ray unless ignored") {
    r = knnocc::cast_ray(map, {0.05f, 0.05f, 0.05f}, {0, 1, 0});
    CHECK(r.status == knnocc::CastStatus::unknown);
    r = knnocc::cast_ray(map, {0.05f, 0.05f, 0.05f}, {-1, 0, 0}, true, 2.0);
    CHECK(r.status == knnocc::CastStatus::max_range);
  }
  SUBCASE("an occupied origin voxel is a hit at once") {
    r = knnocc::cast_ray(map, {1.01f, 0.02f, 0.03f}, {0, 0, 1});
    CHECK(r.status == knnocc::CastStatus::occupied);
    CHECK(r.key == wall);
  }
  SUBCASE("zero direction and NaN origin are invalid") {
    CHECK(knnocc::cast_ray(map, {0.05f, 0.05f, 0.05f}, {0, 0, 0}).status ==
          knnocc::CastStatus::invalid);
    CHECK(knnocc::cast_ray(map, {std::nanf(""), 0, 0}, {1, 0, 0}).status ==
          knnocc::CastStatus::invalid);
  }
}
