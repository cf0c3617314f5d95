// ScanInserter (insertion/scan_inserter.hpp): OctoMap's insertPointCloud semantics, against a
// plain set-based re-statement.
#include <doctest/doctest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <list>
#include <map>
#include <set>
#include <vector>

#include <knnocc/insertion/scan_inserter.hpp>

#include "test_support.hpp"

using knnocc::OccupancyMap;
using knnocc::OcKey;
using knnocc::Point3f;
using knnocc::WideKey;

namespace {

// insertPointCloud written the obvious way (OctoMap's computeUpdate with key sets), used as the
// oracle for the mask-based inserter.
template <class Key>
void reference_insert(OccupancyMap<Key>& map, const Point3f& o, const std::vector<Point3f>& pts,
                      double max_range, bool discretize) {
  const auto& g = map.grid();
  std::vector<Point3f> scan;
  if (discretize) {
    std::set<Key> seen;
    for (const auto& p : pts) {
      Key k;
      if (g.point_to_key(p, k) && seen.insert(k).second)
        scan.push_back({float(g.index_to_coord(k[0])), float(g.index_to_coord(k[1])),
                        float(g.index_to_coord(k[2]))});
    }
  } else {
    for (const auto& p : pts)
      if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) scan.push_back(p);
  }
  std::set<Key> free_cells, occupied_cells;
  std::vector<Key> ray;
  for (const auto& p : scan) {
    const float dx = p.x - o.x, dy = p.y - o.y, dz = p.z - o.z;
    const double norm = std::sqrt(double(dx * dx + dy * dy + dz * dz));
    if (max_range < 0 || norm <= max_range) {
      if (knnocc::compute_ray_keys(g, o, p, ray)) free_cells.insert(ray.begin(), ray.end());
      Key k;
      if (g.point_to_key(p, k)) occupied_cells.insert(k);
    } else if (knnocc::compute_ray_keys(g, o, knnocc::truncate_ray(o, p, max_range), ray)) {
      free_cells.insert(ray.begin(), ray.end());
    }
  }
  for (const auto& k : occupied_cells) free_cells.erase(k);
  for (const auto& k : free_cells) map.update(k, knnocc::logodds(0.4));
  for (const auto& k : occupied_cells) map.update(k, knnocc::logodds(0.7));
}

template <class Key>
std::map<Key, float> dump(const OccupancyMap<Key>& map) {
  std::map<Key, float> out;
  map.for_each_voxel([&](const Key& k, float v) { out[k] = v; });
  return out;
}

std::vector<Point3f> random_scene(knnocc::test::Rng& rng, int n, float extent) {
  std::uniform_real_distribution<float> u(-extent, extent);
  std::vector<Point3f> pts;
  for (int i = 0; i < n; ++i) {
    Point3f p{u(rng), u(rng), u(rng) * 0.3f};
    if (i % 5 == 0) p = pts.empty() ? p : Point3f{pts.back().x + 0.01f, pts.back().y, pts.back().z};
    pts.push_back(p);
  }
  return pts;
}

}  // namespace

TEST_CASE_TEMPLATE("insert.matches_set_based_reference", Key, OcKey, WideKey) {
  knnocc::test::Rng rng(42);
  for (const double max_range : {-1.0, 2.5}) {
    for (const bool discretize : {false, true}) {
      CAPTURE(max_range);
      CAPTURE(discretize);
      OccupancyMap<Key> fast(0.1), slow(0.1);
      knnocc::ScanInserter<Key> inserter(fast);
      std::uniform_real_distribution<float> jitter(-0.5f, 0.5f);
      for (int scan = 0; scan < 6; ++scan) {
        const Point3f origin{jitter(rng), jitter(rng), jitter(rng)};
        const auto pts = random_scene(rng, 800, 4.0f);
        inserter.insert_point_cloud(origin, pts, max_range, discretize);
        reference_insert(slow, origin, pts, max_range, discretize);
        REQUIRE(dump(fast) == dump(slow));
      }
    }
  }
}

TEST_CASE("insert.order_independent_and_occupied_wins") {
  knnocc::test::Rng rng(3);
  auto pts = random_scene(rng, 2000, 3.0f);
  OccupancyMap<OcKey> a(0.05), b(0.05);
  knnocc::insert_point_cloud(a, Point3f{}, pts);
  std::shuffle(pts.begin(), pts.end(), rng);
  knnocc::insert_point_cloud(b, Point3f{}, pts);
  CHECK(dump(a) == dump(b));
  // A point whose voxel lies on another point's ray: hit wins, whatever the order.
  for (int order = 0; order < 2; ++order) {
    OccupancyMap<OcKey> m(0.1);
    std::vector<Point3f> two = {{1.05f, 0.05f, 0.05f}, {2.05f, 0.05f, 0.05f}};
    if (order) std::swap(two[0], two[1]);
    const auto st = knnocc::insert_point_cloud(m, Point3f{0.05f, 0.05f, 0.05f}, two);
    OcKey k;
    REQUIRE(m.grid().coord_to_key(1.05, 0.05, 0.05, k));
    CHECK(*m.logodds(k) == knnocc::logodds(0.7));
    CHECK(st.occupied_voxels == 2);
    CHECK(st.free_voxels == 19);  // keys 0..19 minus the hit at 10
  }
}

TEST_CASE("insert.max_range_carves_without_a_hit") {
  OccupancyMap<OcKey> m(0.1);
  const std::vector<Point3f> pts = {{5.05f, 0.05f, 0.05f}};
  const auto st = knnocc::insert_point_cloud(m, Point3f{0.05f, 0.05f, 0.05f}, pts, 2.0);
  CHECK(st.beyond_max_range == 1);
  CHECK(st.occupied_voxels == 0);
  OcKey end_key, last_free;
  REQUIRE(m.grid().coord_to_key(2.05, 0.05, 0.05, end_key));
  REQUIRE(m.grid().coord_to_key(1.95, 0.05, 0.05, last_free));
  CHECK_FALSE(m.logodds(end_key).has_value());  // the truncated end voxel is not freed
  CHECK(m.logodds(last_free) == std::optional<float>(knnocc::logodds(0.4)));
  CHECK(m.count_voxels().occupied == 0);
  CHECK(m.num_voxels() == 20);
  CHECK_THROWS_AS(knnocc::insert_point_cloud(m, Point3f{}, pts, 0.0), std::invalid_argument);
}

TEST_CASE("insert.updates_survive_gaps_and_repeat") {
  // Hits accumulate over scans; a voxel untouched for many scans keeps its value.
  OccupancyMap<OcKey> m(0.1);
  knnocc::ScanInserter<OcKey> ins(m);
  const std::vector<Point3f> wall = {{1.05f, 0.05f, 0.05f}};
  const std::vector<Point3f> elsewhere = {{0.05f, 1.05f, 0.05f}};
  ins.insert_point_cloud(Point3f{0.05f, 0.05f, 0.05f}, wall);
  for (int i = 0; i < 50; ++i) ins.insert_point_cloud(Point3f{0.05f, 0.05f, 0.05f}, elsewhere);
  ins.insert_point_cloud(Point3f{0.05f, 0.05f, 0.05f}, wall);
  OcKey k;
  REQUIRE(m.grid().coord_to_key(1.05, 0.05, 0.05, k));
  CHECK(*m.logodds(k) == knnocc::logodds(0.7) + knnocc::logodds(0.7));
}

TEST_CASE("insert.bad_points_are_skipped_and_counted") {
  OccupancyMap<OcKey> m(0.1);
  const float nan = std::nanf(""), inf = INFINITY;
  const std::vector<Point3f> pts = {
      {nan, 0, 0}, {0, inf, 0}, {1e9f, 0, 0}, {0.55f, 0.05f, 0.05f}, {-inf, -inf, -inf}};
  const auto st = knnocc::insert_point_cloud(m, Point3f{0.05f, 0.05f, 0.05f}, pts);
  CHECK(st.points == 5);
  CHECK(st.nonfinite == 3);
  CHECK(st.out_of_range == 1);
  CHECK(st.occupied_voxels == 1);
  CHECK(m.num_voxels() == 6);
  // A NaN origin inserts nothing at all.
  OccupancyMap<OcKey> n(0.1);
  const auto sn = knnocc::insert_point_cloud(n, Point3f{nan, 0, 0}, pts);
  CHECK_FALSE(sn.origin_valid);
  CHECK(n.empty());
  // Empty cloud: no-op.
  const auto se = knnocc::insert_point_cloud(n, Point3f{}, std::vector<Point3f>{});
  CHECK(se.points == 0);
  CHECK(n.empty());
}

TEST_CASE("insert.point_types_agree") {
  knnocc::test::Rng rng(8);
  const auto pts = random_scene(rng, 500, 2.0f);
  std::vector<Eigen::Vector3f> eig;
  std::vector<std::array<float, 3>> arr;
  for (auto& p : pts) {
    eig.emplace_back(p.x, p.y, p.z);
    arr.push_back({p.x, p.y, p.z});
  }
  OccupancyMap<OcKey> a(0.1), b(0.1), c(0.1);
  knnocc::insert_point_cloud(a, Point3f{}, pts);
  knnocc::insert_point_cloud(b, Eigen::Vector3f(0, 0, 0), eig);
  knnocc::insert_point_cloud(c, std::array<double, 3>{0, 0, 0}, arr);
  CHECK(dump(a) == dump(b));
  CHECK(dump(a) == dump(c));
}

TEST_CASE_TEMPLATE("insert.large_scans_in_chunks_match_one_piece", Key, OcKey, WideKey) {
  // Scans of more than one chunk (ScanInserter collects and walks large scans 4096 points at a
  // time, applies them once): against the set-based oracle and against the one-piece path (a
  // std::list has no random access, so it is inserted in one piece). NaN/Inf points, points on
  // voxel borders, points beyond max_range and in the origin's voxel (NaN/Inf in the first scan
  // only: the second takes the vectorised bounds); two scans with overlapping voxels, so an
  // update applied twice in one scan would show.
  knnocc::test::Rng rng(41);
  std::uniform_real_distribution<float> u(-3.f, 3.f);
  std::uniform_int_distribution<int> cell(-30, 30);
  for (const double max_range : {-1.0, 2.5}) {
    for (const unsigned threads : {1u, 2u}) {
      CAPTURE(max_range);
      CAPTURE(threads);
      OccupancyMap<Key> chunked(0.1), one_piece(0.1), oracle(0.1);
      knnocc::ScanInserter<Key> a(chunked, {}, threads), b(one_piece, {}, threads);
      for (int scan = 0; scan < 2; ++scan) {
        const Point3f origin{0.3f * static_cast<float>(scan), 0.05f, 0.1f};
        std::vector<Point3f> pts;
        // The second scan's last chunk ends in 5 points after its blocks of eight (the vector
        // collect's tail); the first scan's blocks with NaN/Inf go point by point.
        for (int i = 0; i < 12000 + 5 * scan; ++i) {
          Point3f p{u(rng), u(rng), u(rng) * 0.5f};
          if (i % 7 == 0)  // on voxel borders
            p = {0.1f * static_cast<float>(cell(rng)), 0.1f * static_cast<float>(cell(rng)), p.z};
          if (scan == 0 && i % 997 == 0) p.x = std::numeric_limits<float>::quiet_NaN();
          if (scan == 0 && i % 1999 == 0) p.y = std::numeric_limits<float>::infinity();
          if (i % 1499 == 0) p = origin;
          pts.push_back(p);
        }
        const auto sa = a.insert_point_cloud(origin, pts, max_range);
        const std::list<Point3f> listed(pts.begin(), pts.end());
        const auto sb = b.insert_point_cloud(origin, listed, max_range);
        if (threads == 1) reference_insert(oracle, origin, pts, max_range, false);
        CHECK(sa.chunks == (pts.size() + knnocc::ScanInserter<Key>::chunk_points - 1) /
                               knnocc::ScanInserter<Key>::chunk_points);
        CHECK(sa.chunks >= 3);
        CHECK(sb.chunks == 1);
        CHECK(sa.points == sb.points);
        CHECK(sa.nonfinite == sb.nonfinite);
        CHECK((sa.nonfinite > 0) == (scan == 0));  // the second scan: the all-finite bounds
        CHECK(sa.beyond_max_range == sb.beyond_max_range);
        CHECK(sa.ray_keys == sb.ray_keys);
        CHECK(sa.occupied_voxels == sb.occupied_voxels);
        CHECK(sa.free_voxels == sb.free_voxels);
      }
      CHECK(dump(chunked) == dump(one_piece));
      if (threads == 1) CHECK(dump(chunked) == dump(oracle));
      CHECK(chunked.num_voxels() > 10000);
    }
  }
}

TEST_CASE("insert.large_scan_paths_with_far_and_out_of_range_points") {
  // Returns far beyond max_range (even past the key range) do not stop a large scan from going
  // in chunks: their rays end within max_range. Without a max range, a point outside the key
  // range sends the scan down the one-piece path, which counts it. Both against the oracle.
  knnocc::test::Rng rng(43);
  std::uniform_real_distribution<float> u(-4.f, 4.f);
  std::vector<Point3f> pts;
  for (int i = 0; i < 10000; ++i) pts.push_back({u(rng), u(rng), u(rng) * 0.4f});
  const Point3f origin{0.02f, 0.03f, 0.5f};
  for (const double max_range : {3.0, -1.0}) {
    CAPTURE(max_range);
    std::vector<Point3f> scan = pts;
    scan[9000] = {5000.0f, 0.0f, 0.0f};  // past OcKey's +-3276.8 m at 0.1 m
    if (max_range > 0) scan[5000] = {900.0f, -700.0f, 40.0f};
    OccupancyMap<OcKey> map(0.1), oracle(0.1);
    knnocc::ScanInserter<OcKey> inserter(map);
    const auto st = inserter.insert_point_cloud(origin, scan, max_range);
    reference_insert(oracle, origin, scan, max_range, false);
    CHECK(st.chunks == (max_range > 0 ? 3u : 1u));  // 10,000 points in chunks of 4096
    CHECK(st.out_of_range == (max_range > 0 ? 0u : 1u));
    if (max_range > 0)
      CHECK(st.beyond_max_range > 500);
    else
      CHECK(st.beyond_max_range == 0);
    CHECK(dump(map) == dump(oracle));
  }
}
