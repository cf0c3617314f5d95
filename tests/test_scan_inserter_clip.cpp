// SPDX-License-Identifier: BSD-3-Clause
// Clipped scans (ScanInserter::set_clip, LayeredScanInserter::set_clip, insertion/detail/clip.hpp):
// a scan restricted to a box of keys gives every voxel inside exactly what the whole scan gives
// it and touches nothing outside, on every path (dense bits, dense bytes, hashed scratch, several
// threads, rated scans, discretize, max_range), for boxes that hold the origin, boxes the rays
// only cross, boxes one voxel thin and boxes no ray reaches. The oracle is the unclipped map,
// restricted to the box; and the clipped maps of a partition of space put together are the
// whole map.

#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <deque>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <knnocc/insertion/layered_scan_inserter.hpp>
#include <knnocc/insertion/scan_inserter.hpp>
#include <knnocc/sensor/octomap_model.hpp>

#include "test_support.hpp"

using namespace knnocc;

namespace {

// Scans around a moving origin: clustered and scattered points up to ~6 m away, points on voxel
// borders, a NaN, one far beyond any max range and one in the origin's voxel.
std::vector<test::Scan> clip_scans(test::Rng& rng, int scans, std::size_t points) {
  std::uniform_real_distribution<float> u(-6.0f, 6.0f), small(-0.05f, 0.05f);
  std::uniform_int_distribution<int> cell(-50, 50);
  std::vector<test::Scan> out;
  for (int s = 0; s < scans; ++s) {
    test::Scan scan;
    scan.origin = {0.37f * static_cast<float>(s) - 0.5f, 0.21f, 0.13f};
    while (scan.points.size() < points) {
      const Point3f c{u(rng), u(rng), 0.4f * u(rng)};
      for (int j = 0; j < 4; ++j)
        scan.points.push_back({c.x + small(rng), c.y + small(rng), c.z + small(rng)});
      scan.points.push_back({0.1f * static_cast<float>(cell(rng)),
                             0.1f * static_cast<float>(cell(rng)), c.z});  // on borders
    }
    scan.points[3] = {std::nanf(""), 0.0f, 0.0f};
    scan.points[7] = {80.0f, -3.0f, 1.0f};
    scan.points[11] = scan.origin;
    out.push_back(std::move(scan));
  }
  return out;
}

// A box of keys around the origin's key: [c + lo, c + hi] per axis.
template <class Key>
KeyBounds<Key> box_around(const Grid<Key>& g, const Point3f& at, const int (&lo)[3],
                          const int (&hi)[3]) {
  Key k;
  REQUIRE(g.point_to_key(at, k));
  KeyBounds<Key> b;
  using I = typename Key::index_type;
  for (int a = 0; a < 3; ++a) {
    b.lo[a] = static_cast<I>(k[a] + lo[a]);
    b.hi[a] = static_cast<I>(k[a] + hi[a]);
  }
  return b;
}

// Boxes around the first origin: one holding it, one the rays only cross, a slab one voxel thin,
// a brick-misaligned one far out on the rays' path, and one no ray reaches.
template <class Key>
std::vector<KeyBounds<Key>> some_boxes(const Grid<Key>& g, const Point3f& o) {
  return {
      box_around(g, o, {-7, -9, -3}, {12, 5, 4}), box_around(g, o, {15, -40, -20}, {37, 40, 20}),
      box_around(g, o, {-60, 3, -20}, {60, 3, 20}), box_around(g, o, {-27, 11, -2}, {-15, 23, 9}),
      box_around(g, o, {-60, -60, 30}, {60, 60, 40})};
}

template <class Key>
KeyBounds<Key> brick_aligned(KeyBounds<Key> b) {
  using I = typename Key::index_type;
  for (int a = 0; a < 3; ++a) {
    b.lo[a] = static_cast<I>(b.lo[a] & ~7u);
    b.hi[a] = static_cast<I>(b.hi[a] | 7u);
  }
  return b;
}

// The boxes below, and the same grown to whole bricks (a tile's shape: scans from inside then walk
// their rays whole, crossing rays walk on from their entry voxel on the fast path).
template <class Key>
std::vector<KeyBounds<Key>> clip_boxes(const Grid<Key>& g, const Point3f& o) {
  std::vector<KeyBounds<Key>> boxes = some_boxes(g, o);
  const std::size_t n = boxes.size();
  for (std::size_t i = 0; i < n; ++i) boxes.push_back(brick_aligned(boxes[i]));
  return boxes;
}

template <class Map, class Key>
std::map<std::uint64_t, float> restricted(const Map& map, const KeyBounds<Key>& box) {
  std::map<std::uint64_t, float> out;
  map.for_each_voxel([&](const Key& k, float v) {
    if (box.contains(k)) out[k.pack()] = v;
  });
  return out;
}

struct Path {
  const char* name;
  unsigned threads;
  std::size_t scratch_limit;
};

}  // namespace

TEST_CASE_TEMPLATE("clip: a clipped scan is the whole scan inside the box, nothing outside", Key,
                   OcKey, WideKey) {
  test::Rng rng(5);
  const std::vector<test::Scan> scans = clip_scans(rng, 3, 6000);
  const Path paths[] = {{"dense", 1, std::size_t{384} << 20},
                        {"hashed", 1, 0},
                        {"dense, two threads", 2, std::size_t{384} << 20},
                        {"hashed, two threads", 2, 0}};
  const Grid<Key> grid(0.1);
  for (const double max_range : {-1.0, 3.0})
    for (const bool rated : {false, true})
      for (const bool discretize : {false, true}) {
        if (rated && discretize) continue;
        for (const Path& path : paths) {
          CAPTURE(max_range);
          CAPTURE(rated);
          CAPTURE(discretize);
          const std::string name = path.name;
          CAPTURE(name);
          OccupancyMap<Key> whole(0.1);
          ScanInserter<Key> full(whole, {}, path.threads);
          full.set_scratch_limit(path.scratch_limit);
          const std::vector<KeyBounds<Key>> boxes = clip_boxes(grid, scans[0].origin);
          std::deque<OccupancyMap<Key>> tiles;
          for (std::size_t b = 0; b < boxes.size(); ++b) tiles.emplace_back(0.1);
          std::deque<ScanInserter<Key>> clipped;
          for (std::size_t b = 0; b < boxes.size(); ++b) {
            clipped.emplace_back(tiles[b], OctoMapModel{}, path.threads);
            clipped.back().set_scratch_limit(path.scratch_limit);
            clipped.back().set_clip(boxes[b]);
          }
          for (const test::Scan& s : scans) {
            std::vector<EndpointRating> ratings;
            for (std::size_t i = 0; i < s.points.size(); ++i)
              ratings.push_back({0.3f * static_cast<float>(i % 7) - 0.8f, i % 3 != 0});
            auto insert = [&](ScanInserter<Key>& in) {
              return rated ? in.insert_rated(s.origin, s.points, ratings, max_range)
                           : in.insert_point_cloud(s.origin, s.points, max_range, discretize);
            };
            insert(full);
            for (auto& c : clipped) insert(c);
          }
          for (std::size_t b = 0; b < boxes.size(); ++b) {
            CAPTURE(b);
            const auto expect = restricted(whole, boxes[b]);
            CHECK(test::voxel_values(tiles[b]) == expect);
            if (b % 5 < 4) CHECK(expect.size() > 50);  // the box is really crossed
            if (b == 4) CHECK(expect.empty());         // above every ray
          }
        }
      }
}

TEST_CASE("clip: the clipped maps of a partition of space are the whole map") {
  // Eight octants around a point that the rays cross in every direction, through the large-scan
  // path (chunks are off when clipped: the same map either way).
  test::Rng rng(9);
  const std::vector<test::Scan> scans = clip_scans(rng, 4, 12000);
  OccupancyMap<OcKey> whole(0.05), joined(0.05);
  ScanInserter<OcKey> full(whole);
  OcKey c;
  REQUIRE(whole.grid().point_to_key(Point3f{0.9f, -0.4f, 0.0f}, c));
  for (int octant = 0; octant < 8; ++octant) {
    KeyBounds<OcKey> box;
    for (int a = 0; a < 3; ++a) {
      const bool upper = (octant >> a) & 1;
      box.lo[a] = upper ? c[a] : 0;
      box.hi[a] = upper ? 65535 : static_cast<std::uint16_t>(c[a] - 1);
    }
    OccupancyMap<OcKey> part(0.05);
    ScanInserter<OcKey> in(part);
    in.set_clip(box);
    for (const test::Scan& s : scans) in.insert_point_cloud(s.origin, s.points);
    std::size_t outside = 0;
    part.for_each_voxel([&](const OcKey& k, float v) {
      outside += !box.contains(k);
      joined.set(k, v);
    });
    CHECK(outside == 0);
  }
  for (const test::Scan& s : scans) full.insert_point_cloud(s.origin, s.points);
  CHECK(whole.num_voxels() > 100000);
  CHECK(test::voxel_values(joined) == test::voxel_values(whole));
}

TEST_CASE("clip: a clipped layered keyframe is the whole keyframe inside the box") {
  test::Rng rng(13);
  const std::vector<test::Scan> scans = clip_scans(rng, 3, 4000);
  const RayLayers layers{-0.4f, -0.1f, 2.0};
  const Grid<OcKey> grid(0.1);
  for (const double max_range : {-1.0, 4.0}) {
    CAPTURE(max_range);
    OccupancyMap<OcKey> whole(0.1);
    LayeredScanInserter<OcKey> full(whole, OctoMapModel{});
    const auto boxes = clip_boxes(grid, scans[0].origin);
    std::deque<OccupancyMap<OcKey>> tiles;
    for (std::size_t b = 0; b < boxes.size(); ++b) tiles.emplace_back(0.1);
    std::deque<LayeredScanInserter<OcKey>> clipped;
    for (std::size_t b = 0; b < boxes.size(); ++b) {
      clipped.emplace_back(tiles[b], OctoMapModel{});
      clipped.back().set_clip(boxes[b]);
    }
    for (const test::Scan& s : scans) {
      std::vector<LayeredRating> r;
      for (std::size_t i = 0; i < s.points.size(); ++i)
        r.push_back(
            {0.2f * static_cast<float>(i % 5) - 0.3f, i % 4 != 0, static_cast<RayLayer>(i % 3)});
      full.insert_layered(s.origin, s.points, r, layers, max_range);
      for (auto& c : clipped) c.insert_layered(s.origin, s.points, r, layers, max_range);
    }
    for (std::size_t b = 0; b < boxes.size(); ++b) {
      CAPTURE(b);
      CHECK(test::voxel_values(tiles[b]) == restricted(whole, boxes[b]));
    }
  }
}

TEST_CASE("clip: a ray's keys inside a box are its whole walk's, for any ray and box") {
  // detail::for_each_ray_key_in (jumping to the entry voxel without walking the voxels before it)
  // against for_each_ray_key filtered by the box: rays in every direction, along axes and
  // diagonals (ties between axes), ending on voxel borders, and boxes around, across and beyond
  // them, one voxel thin too.
  test::Rng rng(23);
  std::uniform_real_distribution<float> u(-4.0f, 4.0f);
  std::uniform_int_distribution<int> cell(-40, 40), size(0, 30), pick(0, 5);
  const Grid<OcKey> grid(0.1);
  std::size_t compared = 0, jumped = 0;
  for (int i = 0; i < 20000; ++i) {
    Point3f o{u(rng), u(rng), u(rng)}, e{u(rng), u(rng), u(rng)};
    switch (pick(rng)) {
      case 0:
        e = {o.x, o.y, e.z};
        break;  // along z
      case 1:
        e = {o.x + 2.5f, o.y + 2.5f, o.z + 2.5f};
        break;  // a diagonal
      case 2:
        e = {0.1f * float(cell(rng)), 0.1f * float(cell(rng)), e.z};
        break;  // on borders
      case 3:
        o = {0.1f * float(cell(rng)), 0.05f, 0.1f * float(cell(rng))};
        break;
      default:
        break;
    }
    OcKey ko, kp;
    REQUIRE(grid.point_to_key(o, ko));
    // A box around a point of the ray (or anywhere near the origin).
    const float f = std::uniform_real_distribution<float>(0.0f, 1.2f)(rng);
    REQUIRE(grid.point_to_key(
        Point3f{o.x + f * (e.x - o.x), o.y + f * (e.y - o.y), o.z + f * (e.z - o.z)}, kp));
    const OcKey& around = pick(rng) == 0 ? ko : kp;
    detail::KeyBox box;
    for (int a = 0; a < 3; ++a) {
      box.lo[a] = around[a] + cell(rng) / 8 - 2;
      box.hi[a] = box.lo[a] + (pick(rng) == 0 ? 0 : size(rng) / 3);
    }
    std::vector<std::uint64_t> expect, got;
    for_each_ray_key(grid, o, e, [&](const OcKey& k) {
      const std::int64_t kk[3] = {k[0], k[1], k[2]};
      if (detail::box_contains(box, kk)) expect.push_back(k.pack());
    });
    detail::for_each_ray_key_in(grid, o, e, box, [&](const OcKey& k) { got.push_back(k.pack()); });
    CHECK(got == expect);
    ++compared;
    const std::int64_t ok[3] = {ko[0], ko[1], ko[2]};
    jumped += !expect.empty() && !detail::box_contains(box, ok);
  }
  CHECK(jumped > 3000);  // many rays entered a box they started outside
  MESSAGE(compared << " rays, " << jumped << " entered from outside");
}
