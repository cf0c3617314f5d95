// sensor/map_point_ledger.hpp: views per keyframe, parallax, and contradictions against a
// brute-force test of every ray against every point.

#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <vector>

#include <knnocc/sensor/map_point_ledger.hpp>

using namespace knnocc;

TEST_CASE("ledger: views once per keyframe, first position and direction kept, parallax") {
  OccupancyMap<OcKey> map(0.1);
  MapPointLedger l;
  const Point3d o{0, 0, 0};
  l.observe(5, {1, 0, 0}, o, 0, map.grid());
  l.observe(5, {1, 0, 0}, o, 0, map.grid());
  const auto& e = l.observe(5, {9, 9, 9}, Point3d{1, -1, 0}, 1, map.grid());
  CHECK(e.views == 2);
  CHECK(e.first == 0);  // its creator
  CHECK(e.last == 1);
  CHECK(e.position.x == 1.0);
  CHECK(MapPointLedger::parallax(e, {1, 0, 0}, Point3d{1, -1, 0}) == doctest::Approx(M_PI / 2));
}

TEST_CASE("ledger: contradictions equal a brute-force count; rejected evidence taken back") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  OccupancyMap<OcKey> map(0.1);
  MapPointLedger l;
  std::vector<Point3d> pts;
  for (std::uint64_t id = 0; id < 300; ++id) {
    pts.push_back({u(rng), u(rng), u(rng) * 0.2});
    l.observe(id, pts.back(), Point3d{0, 0, 0}, 0, map.grid());
    l.find(id)->added = 1.0f;
    OcKey k;
    REQUIRE(map.grid().point_to_key(pts.back(), k));
    map.update(k, 1.0f);
  }
  const double radius = 0.08, margin = 0.3;
  std::vector<std::uint32_t> expect(pts.size(), 0);
  std::size_t total = 0;
  for (std::size_t kf = 1; kf <= 5; ++kf) {
    const Point3d o{u(rng), u(rng), 0.5};
    std::vector<Point3d> ends;
    std::vector<EndpointRating> r;
    for (int i = 0; i < 400; ++i) {
      ends.push_back({u(rng) * 2, u(rng) * 2, u(rng) * 0.3});
      r.push_back({0.0f, i % 5 != 0});  // some endpoints cast no ray
    }
    // Brute force: a ray passing within radius, ending > margin beyond, crossing its voxel.
    for (std::size_t p = 0; p < pts.size(); ++p) {
      bool hit = false;
      OcKey pk;
      REQUIRE(map.grid().point_to_key(pts[p], pk));
      for (std::size_t j = 0; j < ends.size() && !hit; ++j) {
        if (!r[j].casts_ray) continue;
        const double ux = ends[j].x - o.x, uy = ends[j].y - o.y, uz = ends[j].z - o.z;
        const double len = std::sqrt(ux * ux + uy * uy + uz * uz);
        if (!(len > margin)) continue;
        const double px = pts[p].x - o.x, py = pts[p].y - o.y, pz = pts[p].z - o.z;
        const double t = (px * ux + py * uy + pz * uz) / len;
        if (!(t > 0 && t < len - margin) || px * px + py * py + pz * pz - t * t > radius * radius)
          continue;
        const double f = (len - margin) / len;
        const Point3f stop = detail::to_point3f(Point3d{o.x + ux * f, o.y + uy * f, o.z + uz * f});
        std::vector<OcKey> keys;
        compute_ray_keys(map.grid(), detail::to_point3f(o), stop, keys);
        for (const OcKey& k : keys) hit = hit || k == pk;
      }
      expect[p] += hit;
      total += hit;
    }
    l.contradict(o, ends, r, kf, radius, margin, map,
                 [](std::uint32_t, std::uint32_t) { return false; });
  }
  REQUIRE(total > 20);
  for (std::size_t p = 0; p < pts.size(); ++p) {
    CAPTURE(p);
    CHECK(l.find(p)->contra == expect[p]);
  }
  // Now reject the points one ray touches: the 1.0 of evidence each added is taken back.
  std::size_t pick = pts.size();
  for (std::size_t p = 0; p < pts.size() && pick == pts.size(); ++p)
    if (std::hypot(pts[p].x, pts[p].y) > 0.8 && !l.find(p)->rejected) pick = p;
  REQUIRE(pick < pts.size());
  OcKey k;
  REQUIRE(map.grid().point_to_key(pts[pick], k));
  const float before = *map.logodds(k);
  const Point3d o{0, 0, 0};
  const Point3d through{pts[pick].x * 3, pts[pick].y * 3, pts[pick].z * 3};
  std::vector<EndpointRating> ray{{0.0f, true}};
  std::size_t in_voxel = 0;  // points sharing the voxel, all on the ray's way
  for (const Point3d& q : pts) {
    OcKey qk;
    REQUIRE(map.grid().point_to_key(q, qk));
    in_voxel += qk == k;
  }
  const std::size_t rejected = l.contradict(o, {through}, ray, 99, 0.05, 0.3, map,
                                            [](std::uint32_t, std::uint32_t) { return true; });
  CHECK(rejected >= 1);
  CHECK(l.find(pick)->rejected);
  CHECK(l.find(pick)->added == 0.0f);
  CHECK(*map.logodds(k) <= before - 1.0f + 1e-6f);
  CHECK(*map.logodds(k) >= before - float(in_voxel) - 1e-6f);
}
