// sensor/map_point_ledger.hpp and sensor/voxel_tally.hpp: views once per keyframe, first position
// kept, stable indices; see-throughs per voxel against a brute-force walk of every shortened ray,
// and the dense walk against the ray-by-ray walk.

#include <doctest/doctest.h>

#include <cmath>
#include <map>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include <knnocc/map/occupancy_map.hpp>
#include <knnocc/raycast/dda.hpp>
#include <knnocc/sensor/map_point_ledger.hpp>
#include <knnocc/sensor/voxel_tally.hpp>

using namespace knnocc;

TEST_CASE("ledger: views once per keyframe, first position and creator kept, stable indices") {
  MapPointLedger l;
  bool fresh = false, counted = false;
  CHECK(l.observe(5, {1, 0, 0}, 0, fresh, counted) == 0);
  CHECK(fresh);
  CHECK(counted);
  l.observe(5, {1, 0, 0}, 0, fresh, counted);  // the same keyframe again
  CHECK_FALSE(fresh);
  CHECK_FALSE(counted);
  l.observe(9, {2, 0, 0}, 1, fresh, counted);
  const auto& e = l.at(l.observe(5, {9, 9, 9}, 3, fresh, counted));
  CHECK(counted);
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
  // Cells for the voxels of a few hundred map points: on_pass reports those.
  std::set<std::uint32_t> cells;
  std::map<std::uint32_t, std::uint64_t> cell_key;
  for (int i = 0; i < 300; ++i) {
    OcKey k;
    REQUIRE(map.grid().coord_to_key(u(rng), u(rng), u(rng) * 0.2 + 1.0, k));
    const std::uint32_t s = tally.slot(k);
    CHECK(tally.slot(k) == s);
    CHECK(tally.find(k) == s);
    cells.insert(s);
    cell_key[s] = k.pack();
  }
  CHECK(tally.size() == cells.size());
  std::map<std::uint64_t, std::uint32_t> want;
  for (std::uint32_t kf = 0; kf < 12; ++kf) {
    const Point3d origin{u(rng) * 0.3, u(rng) * 0.3, 0.0};
    std::vector<Point3d> pts;
    for (int j = 0; j < 80; ++j) pts.push_back({u(rng), u(rng), u(rng) * 0.2 + 1.0});
    const double margin = 0.1 + 0.02 * kf;
    std::set<std::uint32_t> reported;  // on_pass: once per voxel with a cell the keyframe crossed
    std::size_t calls = 0;
    tally.add_keyframe(
        map.grid(), origin, pts, margin, kf, [](std::size_t j) { return j % 7 != 3; },
        [&](std::uint32_t slot) {
          reported.insert(slot);
          ++calls;
        });                           // some rays left out
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
    std::set<std::uint32_t> expect;
    for (const std::uint32_t s : cells)
      if (crossed.count(cell_key[s])) expect.insert(s);
    CHECK(calls == expect.size());
    CHECK(reported == expect);
  }
  std::size_t checked = 0, twice = 0;
  for (const auto& [key, passes] : want) {
    CHECK(tally.passes(OcKey::unpack(key)) == passes);
    ++checked;
    twice += passes >= 2;
  }
  for (const std::uint32_t s : cells) {
    const auto it = want.find(cell_key[s]);
    CHECK(tally.passes_at(s) == (it == want.end() ? 0u : it->second));
  }
  CHECK(checked > 1000);
  CHECK(twice > 100);  // the keyframes overlap: counts above one are exercised
  OcKey far;           // a voxel no ray reached
  REQUIRE(map.grid().coord_to_key(50.0, 50.0, 50.0, far));
  CHECK(tally.passes(far) == 0);
  CHECK(tally.find(far) == VoxelTally::kNone);
}

TEST_CASE(
    "voxel tally: the dense walk counts as the ray-by-ray walk, crossings in the same order") {
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  const Grid<OcKey> grid(0.1);
  VoxelTally dense, hashed;
  hashed.set_dense_walk(false);
  for (int i = 0; i < 400; ++i) {  // cells where the rays pass, so that many rays cross some
    OcKey k;
    REQUIRE(grid.coord_to_key(u(rng), u(rng), 0.6 + u(rng) * 0.3, k));
    CHECK(dense.slot(k) == hashed.slot(k));
  }
  // (keyframe, ray, cell) of every on_cross and (keyframe, cell) of every on_pass, in call order.
  using Calls = std::vector<std::tuple<std::uint32_t, std::size_t, std::uint32_t>>;
  Calls dense_calls, hashed_calls;
  std::set<std::uint64_t> reached;
  std::size_t crossings = 0;
  for (std::uint32_t kf = 0; kf < 16; ++kf) {
    const Point3d origin{u(rng) * 0.3, u(rng) * 0.3, 0.0};
    std::vector<Point3d> pts;
    for (int j = 0; j < 120; ++j) pts.push_back({u(rng), u(rng), u(rng) * 0.2 + 1.2});
    if (kf == 5) pts.push_back({3000.0, 0.0, 1.0});  // a box too large: the hashed walk for both
    std::vector<std::uint32_t> witness(pts.size());
    for (std::size_t j = 0; j < pts.size(); ++j)  // repeated witnesses, some rays without one
      witness[j] = j % 5 == 0 ? VoxelTally::kNone : static_cast<std::uint32_t>(j % 37);
    auto run = [&](VoxelTally& t, Calls& calls) {
      t.add_keyframe(
          grid, origin, pts, 0.15, kf, [](std::size_t j) { return j % 11 != 4; },
          [&](std::size_t j) { return witness[j]; },
          [&](std::uint32_t slot) { calls.emplace_back(kf, ~std::size_t{0}, slot); },
          [&](std::size_t j, std::uint32_t slot) { calls.emplace_back(kf, j, slot); });
    };
    run(dense, dense_calls);
    run(hashed, hashed_calls);
    for (const Point3d& p : pts) {
      std::vector<OcKey> keys;
      if (compute_ray_keys(grid, detail::to_point3f(origin), detail::to_point3f(p), keys))
        for (const OcKey& k : keys) reached.insert(k.pack());
    }
  }
  for (const auto& c : hashed_calls) crossings += std::get<1>(c) != ~std::size_t{0};
  CHECK(crossings > 200);  // rays cross cells, often more than one
  CHECK(dense_calls == hashed_calls);
  for (const std::uint64_t k : reached)
    CHECK(dense.passes(OcKey::unpack(k)) == hashed.passes(OcKey::unpack(k)));
  for (std::uint32_t s = 0; s < dense.size(); ++s) CHECK(dense.passes_at(s) == hashed.passes_at(s));
  CHECK(dense.memory_usage() > hashed.memory_usage());  // the dense walk ran (its scratch is kept)
}
