// OccupancyMap (map/occupancy_map.hpp): clamping, iteration, coarse queries, compaction, change
// detection, key types.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <random>
#include <utility>
#include <vector>

#include <knnocc/insertion/scan_inserter.hpp>
#include <knnocc/map/detail/brick_access.hpp>
#include <knnocc/map/occupancy_map.hpp>

#include "test_support.hpp"

using knnocc::OccupancyMap;
using knnocc::OcKey;
using knnocc::WideKey;

namespace {
template <class Key>
void fill_random(OccupancyMap<Key>& map, std::map<Key, float>& truth, int n, std::uint64_t seed,
                 int spread) {
  knnocc::test::Rng rng(seed);
  std::uniform_int_distribution<int> off(-spread, spread);
  std::uniform_int_distribution<int> pick(0, 3);
  const float deltas[] = {0.85f, -0.4f, 0.3f, -1.1f};
  for (int i = 0; i < n; ++i) {
    Key k;
    for (int a = 0; a < 3; ++a)
      k[a] = static_cast<typename Key::index_type>(Key::center + off(rng));
    const float d = deltas[pick(rng)];
    if (truth.find(k) == truth.end())
      if (const auto prior = map.logodds(k)) truth[k] = *prior;  // voxel set before this call
    const float v = map.update(k, d);
    // Reference rule, written out independently of the map.
    auto it = truth.find(k);
    const auto& p = map.params();
    if (it == truth.end()) {
      truth[k] = std::min(std::max(0.0f + d, p.clamp_min), p.clamp_max);
    } else if (!((d >= 0 && it->second >= p.clamp_max) || (d <= 0 && it->second <= p.clamp_min))) {
      it->second = std::min(std::max(it->second + d, p.clamp_min), p.clamp_max);
    }
    REQUIRE(v == truth[k]);
  }
}
}  // namespace

TEST_CASE("map.octomap_default_parameters") {
  const knnocc::OccupancyParams p;
  CHECK(p.clamp_min == doctest::Approx(-2.00002789).epsilon(1e-8));
  CHECK(p.clamp_max == doctest::Approx(3.51103067).epsilon(1e-8));
  CHECK(p.occupancy_threshold == 0.0f);
  CHECK(knnocc::logodds(0.7) == doctest::Approx(0.847297847).epsilon(1e-8));
  CHECK(knnocc::logodds(0.4) == doctest::Approx(-0.405465096).epsilon(1e-8));
  CHECK(knnocc::probability(knnocc::logodds(0.7)) == doctest::Approx(0.7));
  knnocc::OccupancyParams bad;
  bad.clamp_min = 1.0f;
  bad.clamp_max = 0.5f;
  CHECK_THROWS_AS(OccupancyMap<OcKey>(0.1, bad), std::invalid_argument);
}

TEST_CASE("map.clamping_and_early_abort") {
  OccupancyMap<OcKey> map(0.1);
  const OcKey k(100, 200, 300);
  const float hit = knnocc::logodds(0.7), miss = knnocc::logodds(0.4);
  CHECK_FALSE(map.logodds(k).has_value());
  CHECK(map.update(k, hit) == hit);  // new voxels start at 0
  float expected = hit;
  for (int i = 0; i < 10; ++i) {
    const float v = map.update(k, hit);
    expected = std::min(expected + hit, map.params().clamp_max);
    CHECK(v == expected);
  }
  CHECK(*map.logodds(k) == map.params().clamp_max);
  // At the upper bound a miss still counts, from the bound.
  CHECK(map.update(k, miss) == map.params().clamp_max + miss);
  for (int i = 0; i < 30; ++i) map.update(k, miss);
  CHECK(*map.logodds(k) == map.params().clamp_min);
  CHECK(map.update(k, miss) == map.params().clamp_min);  // early abort: unchanged
  CHECK(map.is_occupied(k) == std::optional<bool>(false));
  map.set(k, 100.0f);
  CHECK(*map.logodds(k) == map.params().clamp_max);  // set() clamps
  CHECK(map.num_voxels() == 1);
}

TEST_CASE_TEMPLATE("map.iteration_bbox_and_coarse_queries", Key, OcKey, WideKey) {
  OccupancyMap<Key> map(0.2);
  std::map<Key, float> truth;
  fill_random(map, truth, 20000, 11, 40);
  CHECK(map.num_voxels() == truth.size());

  std::map<Key, float> seen;
  map.for_each_voxel([&](const Key& k, float v) { CHECK(seen.emplace(k, v).second); });
  CHECK(seen == truth);

  const auto counts = map.count_voxels();
  std::size_t occ = 0;
  for (auto& [k, v] : truth) occ += v >= 0.0f;
  CHECK(counts.occupied == occ);
  CHECK(counts.free == truth.size() - occ);

  // Bounding boxes: one small (probes bricks) and one large (scans bricks).
  for (int half : {3, 30, 200}) {
    Key lo, hi;
    for (int a = 0; a < 3; ++a) {
      lo[a] = static_cast<typename Key::index_type>(Key::center - half + a);
      hi[a] = static_cast<typename Key::index_type>(Key::center + half / 2);
    }
    std::size_t expect = 0, got = 0;
    for (auto& [k, v] : truth)
      expect += k[0] >= lo[0] && k[0] <= hi[0] && k[1] >= lo[1] && k[1] <= hi[1] && k[2] >= lo[2] &&
                k[2] <= hi[2];
    map.for_each_voxel_in_bbox(lo, hi, [&](const Key& k, float v) {
      ++got;
      CHECK(truth.at(k) == v);
    });
    CHECK(got == expect);
  }

  // Coarse depth: the max over known leaves below the node, as OctoMap's inner nodes.
  knnocc::test::Rng rng(5);
  std::uniform_int_distribution<int> off(-45, 45);
  for (int i = 0; i < 300; ++i) {
    Key probe;
    for (int a = 0; a < 3; ++a)
      probe[a] = static_cast<typename Key::index_type>(Key::center + off(rng));
    for (int d = Key::depth; d >= Key::depth - 7; --d) {
      const int shift = Key::depth - d;
      std::optional<float> expect;
      for (auto& [k, v] : truth) {
        bool inside = true;
        for (int a = 0; a < 3; ++a) inside = inside && (k[a] >> shift) == (probe[a] >> shift);
        if (inside) expect = expect ? std::max(*expect, v) : v;
      }
      CHECK(map.logodds_at_depth(probe, d) == expect);
    }
  }
  // The root holds the max of everything.
  float root = -1e9f;
  for (auto& [k, v] : truth) root = std::max(root, v);
  CHECK(map.logodds_at_depth(Key{}, 0) == std::optional<float>(root));
}

TEST_CASE("map.compaction_keeps_every_query") {
  OccupancyMap<OcKey> map(0.1);
  // A solid free block (uniform bricks) and a noisy region (dense bricks).
  for (int x = 0; x < 32; ++x)
    for (int y = 0; y < 32; ++y)
      for (int z = 0; z < 16; ++z) map.update(OcKey(32768 + x, 32768 + y, 32768 + z), -0.4f);
  std::map<OcKey, float> truth;
  fill_random(map, truth, 3000, 3, 10);
  std::map<OcKey, float> before;
  map.for_each_voxel([&](const OcKey& k, float v) { before[k] = v; });
  std::vector<std::optional<float>> coarse_before;
  for (int d = 10; d <= 16; ++d)
    for (int i = 0; i < 40; ++i)
      coarse_before.push_back(
          map.logodds_at_depth(OcKey(32768 + i, 32768 + 2 * i, 32768 + i % 5), d));

  const std::size_t mem_before = map.memory_usage();
  const std::size_t compacted = map.compact();
  CHECK(compacted > 0);
  CHECK(map.memory_usage() < mem_before);

  std::map<OcKey, float> after;
  map.for_each_voxel([&](const OcKey& k, float v) { after[k] = v; });
  CHECK(after == before);
  std::size_t j = 0;
  for (int d = 10; d <= 16; ++d)
    for (int i = 0; i < 40; ++i)
      CHECK(map.logodds_at_depth(OcKey(32768 + i, 32768 + 2 * i, 32768 + i % 5), d) ==
            coarse_before[j++]);
  // Writing into a compacted brick expands it again, without touching its neighbours.
  const OcKey k(32768 + 1, 32768 + 1, 32768 + 1);
  const float v0 = *map.logodds(k);
  map.update(k, 0.85f);
  CHECK(*map.logodds(k) == v0 + 0.85f);
  CHECK(*map.logodds(OcKey(32768 + 2, 32768 + 1, 32768 + 1)) ==
        before[OcKey(32768 + 2, 32768 + 1, 32768 + 1)]);
}

TEST_CASE("map.change_detection_follows_octomap") {
  OccupancyMap<OcKey> map(0.1);
  map.enable_change_detection(true);
  const OcKey a(10, 10, 10), b(11, 10, 10);
  map.update(a, -0.4f);  // new -> recorded as created
  map.update(b, 0.85f);
  CHECK(map.num_changed_keys() == 2);
  map.reset_change_detection();
  map.update(a, -0.4f);  // stays free: no record
  CHECK(map.num_changed_keys() == 0);
  map.update(b, -2.0f);  // occupied -> free: recorded as a flip
  std::map<OcKey, bool> got;
  map.for_each_changed_key([&](const OcKey& k, bool created) { got[k] = created; });
  CHECK(got == std::map<OcKey, bool>{{b, false}});
  map.update(b, 3.0f);  // flips back: record removed
  CHECK(map.num_changed_keys() == 0);
  const OcKey c(12, 10, 10);
  map.update(c, 0.85f);  // new: recorded as created
  map.update(c, -2.0f);  // then flips: the created record stays, as in OctoMap
  std::map<OcKey, bool> after_flip;
  map.for_each_changed_key([&](const OcKey& k, bool created) { after_flip[k] = created; });
  CHECK(after_flip == std::map<OcKey, bool>{{c, true}});
  map.reset_change_detection();
  map.enable_change_detection(false);
  map.update(OcKey(1, 2, 3), 1.0f);
  CHECK(map.num_changed_keys() == 0);
}

TEST_CASE("map.accessor_matches_map_updates") {
  OccupancyMap<OcKey> a(0.1), b(0.1);
  auto acc = b.accessor();
  knnocc::test::Rng rng(9);
  std::uniform_int_distribution<int> off(-20, 20);
  for (int i = 0; i < 5000; ++i) {
    const OcKey k(static_cast<std::uint16_t>(32768 + off(rng)),
                  static_cast<std::uint16_t>(32768 + off(rng)), 32768);
    const float d = (i % 3) ? -0.4f : 0.85f;
    CHECK(a.update(k, d) == acc.update(k, d));
  }
  CHECK(a.num_voxels() == b.num_voxels());
  a.clear();
  CHECK(a.empty());
  CHECK(a.num_bricks() == 0);
}

TEST_CASE("map.copy_brick_from_makes_a_brick_equal") {
  using Layout = knnocc::BrickLayout<OcKey>;
  OccupancyMap<OcKey> a(0.1), b(0.1);
  const OcKey k1(32768, 32768, 32768), k2(32769, 32770, 32771), far(40000, 32768, 32768);
  a.update(k1, 0.85f);
  a.update(far, -0.4f);
  b.update(k2, -0.4f);
  b.update(far, 0.85f);
  const std::uint64_t brick = Layout::brick_of(k1);
  REQUIRE(Layout::brick_of(k2) == brick);
  knnocc::detail::BrickWriter<OcKey> writer(a);  // the live mapper's regional replay
  writer.copy_brick_from(b, brick);              // a's brick now holds b's voxels only
  CHECK_FALSE(a.is_known(k1));
  CHECK(a.logodds(k2) == b.logodds(k2));
  CHECK(a.logodds(far) == -0.4f);  // other bricks untouched
  CHECK(a.num_voxels() == 2);
  const OccupancyMap<OcKey> empty(0.1);
  writer.copy_brick_from(empty, brick);  // absent in the source: unknown here
  CHECK_FALSE(a.is_known(k2));
  CHECK(a.num_voxels() == 1);
  b.compact();  // a uniform brick (no value array) copies too
  writer.copy_brick_from(b, brick);
  CHECK(a.logodds(k2) == b.logodds(k2));
  CHECK(a.num_voxels() == 2);
  std::size_t seen = 0;
  a.for_each_voxel([&](const OcKey&, float) { ++seen; });
  CHECK(seen == a.num_voxels());
}

// A map's memory limit: the write that would pass it is refused (MemoryLimitError) before any
// allocation, the map stays as it was and keeps working within what it has.
TEST_CASE("map.memory_limit_refuses_the_write_that_would_pass_it") {
  OccupancyMap<OcKey> map(0.1);
  const std::size_t limit = 300000;
  map.set_memory_limit(limit);
  CHECK(map.memory_limit() == limit);
  std::size_t made = 0;
  bool refused = false;
  std::uint16_t x = 32768;
  for (; made < 10000; ++made, x = static_cast<std::uint16_t>(x + 8)) {  // a new brick each
    const std::size_t before = map.memory_usage(), known = map.num_voxels();
    try {
      map.update(OcKey(x, 32768, 32768), 0.85f);
    } catch (const knnocc::MemoryLimitError& e) {
      refused = true;
      CHECK(e.limit() == limit);
      CHECK(e.needed() > limit);
      CHECK(std::string(e.what()).find("map memory limit of 0.3 MB") != std::string::npos);
      CHECK(map.memory_usage() == before);  // nothing allocated
      CHECK(map.num_voxels() == known);
      CHECK_FALSE(map.is_known(OcKey(x, 32768, 32768)));
      break;
    }
    REQUIRE(map.memory_usage() <= limit);
  }
  REQUIRE(refused);
  CHECK(made > 50);  // the limit was used, not refused at once
  // Voxels of existing bricks can still be written; earlier values are intact.
  CHECK(map.update(OcKey(32769, 32768, 32768), 0.85f) == doctest::Approx(0.85f));
  CHECK(*map.logodds(OcKey(32768, 32768, 32768)) == doctest::Approx(0.85f));
  // Without a limit the same write succeeds.
  map.set_memory_limit(0);
  map.update(OcKey(x, 32768, 32768), 0.85f);
  CHECK(map.is_known(OcKey(x, 32768, 32768)));
}

TEST_CASE("map.memory_limit_bounds_a_whole_scan") {
  // 2,000 rays 50 m long in every direction: far more bricks than 1 MB holds.
  std::vector<knnocc::Point3f> pts;
  knnocc::test::Rng rng(5);
  std::normal_distribution<float> n(0.f, 1.f);
  for (int i = 0; i < 2000; ++i) {
    float v[3] = {n(rng), n(rng), n(rng)};
    const float r = 50.f / std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    pts.push_back({v[0] * r, v[1] * r, v[2] * r});
  }
  OccupancyMap<OcKey> limited(0.05);
  limited.set_memory_limit(std::size_t{1} << 20);
  CHECK_THROWS_AS(knnocc::insert_point_cloud(limited, knnocc::Point3f{0, 0, 0}, pts),
                  knnocc::MemoryLimitError);
  CHECK(limited.memory_usage() <= (std::size_t{1} << 20));
  OccupancyMap<OcKey> unlimited(0.05);
  knnocc::ScanInserter<OcKey> inserter(unlimited);
  inserter.insert_point_cloud(knnocc::Point3f{0, 0, 0}, pts);
  CHECK(unlimited.memory_usage() > (std::size_t{1} << 20));
  // A limit above what the scan needs (the map and the inserter's scratch: the limit covers
  // both) changes nothing.
  OccupancyMap<OcKey> roomy(0.05);
  roomy.set_memory_limit(2 * (unlimited.memory_usage() + inserter.memory_usage()));
  knnocc::insert_point_cloud(roomy, knnocc::Point3f{0, 0, 0}, pts);
  CHECK(roomy.num_voxels() == unlimited.num_voxels());
}
