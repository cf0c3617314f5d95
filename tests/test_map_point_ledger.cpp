// sensor/map_point_ledger.hpp and sensor/voxel_tally.hpp: views once per keyframe, first position
// kept, stable indices; see-throughs per voxel against a brute-force walk of every shortened ray.

#include <doctest/doctest.h>

#include <cmath>
#include <map>
#include <random>
#include <set>
#include <vector>

#include <knnocc/map/occupancy_map.hpp>
#include <knnocc/raycast/dda.hpp>
#include <knnocc/sensor/map_point_ledger.hpp>
#include <knnocc/sensor/voxel_tally.hpp>

using namespace knnocc;

TEST_CASE("ledger: views once per keyframe, first position and creator kept, stable indices") {
  MapPointLedger l;
  bool fresh = false;
  l.observe(5, {1, 0, 0}, 0, fresh);
  CHECK(fresh);
  l.observe(5, {1, 0, 0}, 0, fresh);  // the same keyframe again
  CHECK_FALSE(fresh);
  l.observe(9, {2, 0, 0}, 1, fresh);
  const auto& e = l.observe(5, {9, 9, 9}, 3, fresh);
  CHECK(e.views == 2);
  CHECK(e.first == 0);  // its creator
  CHECK(e.last == 3);
  CHECK(e.position.x == 1.0);
  CHECK(l.size() == 2);
  CHECK(l.index_of(5) == 0);
  CHECK(l.index_of(9) == 1);
  CHECK(l.index_of(7) == MapPointLedger::kNone);
  CHECK(l.find(7) == nullptr);
  CHECK(l.id_at(1) == 9);
  std::vector<std::uint64_t> order;
  l.for_each([&](std::uint64_t id, const MapPointLedger::Point&) { order.push_back(id); });
  CHECK(order == std::vector<std::uint64_t>{5, 9});
}

TEST_CASE("voxel tally: see-throughs equal a brute-force walk, each keyframe once per voxel") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  OccupancyMap<OcKey> map(0.1);
  VoxelTally tally;
  std::map<std::uint64_t, std::uint32_t> want;
  for (std::uint32_t kf = 0; kf < 12; ++kf) {
    const Point3d origin{u(rng) * 0.3, u(rng) * 0.3, 0.0};
    std::vector<Point3d> pts;
    for (int j = 0; j < 80; ++j) pts.push_back({u(rng), u(rng), u(rng) * 0.2 + 1.0});
    const double margin = 0.1 + 0.02 * kf;
    tally.add_keyframe(map.grid(), origin, pts, margin, kf,
                       [](std::size_t j) { return j % 7 != 3; });  // some rays left out
    std::set<std::uint64_t> crossed;  // brute force: the shortened segment, voxel by voxel
    std::vector<OcKey> keys;
    for (std::size_t j = 0; j < pts.size(); ++j) {
      if (j % 7 == 3) continue;
      const Point3d& p = pts[j];
      const double len =
          std::sqrt((p.x - origin.x) * (p.x - origin.x) + (p.y - origin.y) * (p.y - origin.y) +
                    (p.z - origin.z) * (p.z - origin.z));
      if (!(len > margin)) continue;
      const double f = (len - margin) / len;
      const Point3d stop{origin.x + (p.x - origin.x) * f, origin.y + (p.y - origin.y) * f,
                         origin.z + (p.z - origin.z) * f};
      REQUIRE(
          compute_ray_keys(map.grid(), detail::to_point3f(origin), detail::to_point3f(stop), keys));
      for (const OcKey& k : keys) crossed.insert(k.pack());
    }
    for (const std::uint64_t k : crossed) ++want[k];
  }
  std::size_t checked = 0, twice = 0;
  for (const auto& [key, passes] : want) {
    const std::uint32_t s = tally.find(key);
    REQUIRE(s != VoxelTally::kNone);
    CHECK(tally.at(s).passes == passes);
    ++checked;
    twice += passes >= 2;
  }
  CHECK(tally.size() == want.size());
  CHECK(checked > 1000);
  CHECK(twice > 100);  // the keyframes overlap: counts above one are exercised
  // A voxel no ray crossed has no pass; slot() makes it.
  OcKey far;
  REQUIRE(map.grid().coord_to_key(50.0, 50.0, 50.0, far));
  CHECK(tally.find(far.pack()) == VoxelTally::kNone);
  const std::uint32_t s = tally.slot(far.pack());
  CHECK(tally.at(s).passes == 0);
  CHECK(tally.slot(far.pack()) == s);
}
