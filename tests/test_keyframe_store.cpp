// KeyframeStore and reach_of (live/keyframe_store.hpp): the brick box of a keyframe holds every
// voxel its rays touch (the insertion itself is the oracle), with and without max range; the
// store keeps insertion order through removals.
#include <doctest/doctest.h>

#include <random>
#include <vector>

#include <knnocc/insertion/scan_inserter.hpp>
#include <knnocc/live/keyframe_store.hpp>
#include <knnocc/live/rigid_pose.hpp>
#include <knnocc/map/occupancy_map.hpp>
#include <knnocc/sensor/octomap_model.hpp>

#include "test_support.hpp"

using namespace knnocc;

TEST_CASE("keyframe_store.reach_holds_every_touched_voxel") {
  test::Rng rng(17);
  std::uniform_real_distribution<double> u(-6.0, 6.0);
  for (const double res : {0.05, 0.1, 0.37})
    for (const double max_range : {-1.0, 2.5}) {
      CAPTURE(res);
      CAPTURE(max_range);
      for (int trial = 0; trial < 20; ++trial) {
        const Point3d origin{u(rng), u(rng), 0.3 * u(rng)};
        std::vector<Point3d> world;
        for (int j = 0; j < 200; ++j)
          world.push_back({origin.x + u(rng), origin.y + u(rng), origin.z + 0.5 * u(rng)});
        const BrickBox box = reach_of<OcKey>(origin, world, res, max_range);
        OccupancyMap<OcKey> map(res);
        ScanInserter<OcKey, OctoMapModel> inserter(map, OctoMapModel{});
        inserter.insert_point_cloud(origin, world, max_range);
        REQUIRE(map.num_voxels() > 0);
        std::size_t outside = 0;
        map.for_each_voxel([&](const OcKey& k, float) {
          const std::array<std::int64_t, 3> b{k[0] >> kBrickBits, k[1] >> kBrickBits,
                                              k[2] >> kBrickBits};
          outside += !box.contains(b);
        });
        CHECK(outside == 0);
        // and the box is not the whole world: at most a brick of margin around the points
        CHECK(box.volume() < 1e6);
      }
    }
  CHECK(reach_of<OcKey>({0, 0, 0}, {}, 0.1, -1.0).empty());  // no rays, no reach
}

TEST_CASE("keyframe_store.keeps_order_through_removals") {
  KeyframeStore<RigidPose> store;
  for (std::uint64_t id : {5, 3, 9, 1}) {
    LiveKeyframe<RigidPose> kf;
    kf.id = id;
    kf.points.resize(id);
    store.push_back(kf);
  }
  CHECK(store.points() == 18);
  store.erase({0, 1, 0, 0});  // removes id 3
  REQUIRE(store.size() == 3);
  CHECK(store[0].id == 5);
  CHECK(store[1].id == 9);
  CHECK(store[2].id == 1);
  CHECK(store.position(1) == 2);
  CHECK_FALSE(store.contains(3));
  CHECK(store.memory_usage() >= 15 * sizeof(Point3f));
}
