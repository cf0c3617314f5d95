// LayeredScanInserter::insert_layered (the 2022 k-NN model's keyframes): with one layer the map
// ScanInserter::insert_rated makes; with two, the map an oracle computes point by point (rays key
// by key with compute_ray_keys, each voxel's one update chosen hit > strong > weak, updates voxel
// by voxel), over several keyframes so clamping is exercised.

#include <doctest/doctest.h>

#include <cmath>
#include <map>
#include <random>
#include <set>
#include <vector>

#include <knnocc/insertion/layered_scan_inserter.hpp>
#include <knnocc/insertion/scan_inserter.hpp>
#include <knnocc/map/same_voxels.hpp>
#include <knnocc/raycast/dda.hpp>
#include <knnocc/sensor/octomap_model.hpp>

#include "test_support.hpp"

using namespace knnocc;

namespace {

struct LayeredScan {
  Point3f origin;
  std::vector<Point3f> points;
  std::vector<LayeredRating> ratings;
};

// Clustered points up to ~7 m away, so many voxels hold several endpoints and rays of all three
// kinds cross; a NaN point and a far one.
LayeredScan random_scan(test::Rng& rng, float ox) {
  std::uniform_real_distribution<float> u(-5.0f, 5.0f), small(-0.04f, 0.04f), l(-2.0f, 2.0f);
  LayeredScan s;
  s.origin = {ox, 0.3f, 0.2f};
  while (s.points.size() < 3000) {
    const Point3f c{u(rng), u(rng), 0.5f * u(rng)};
    for (int j = 0; j < 3; ++j) {
      s.points.push_back({c.x + small(rng), c.y + small(rng), c.z + small(rng)});
      const auto kind = rng() % 4;
      LayeredRating r;
      r.hit = kind != 3;
      r.logodds = l(rng);
      r.ray = kind == 0 ? RayLayer::none : kind == 3 ? RayLayer::weak : RayLayer::strong;
      s.ratings.push_back(r);
    }
  }
  s.points[17] = {std::nanf(""), 0, 0};
  s.points[99] = {40.0f, 1.0f, 0.0f};
  return s;
}

// The oracle: one keyframe into `map`, each voxel at most once.
void oracle_insert(OccupancyMap<OcKey>& map, const LayeredScan& s, const RayLayers& layers,
                   double max_range) {
  std::map<std::uint64_t, double> hits;
  std::set<std::uint64_t> strong, weak;
  std::vector<OcKey> ray;
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    const Point3f& p = s.points[i];
    if (!std::isfinite(p.x)) continue;
    const LayeredRating& r = s.ratings[i];
    const double range = detail::octomap_norm(p.x - s.origin.x, p.y - s.origin.y, p.z - s.origin.z);
    const bool in = max_range < 0 || range <= max_range;
    if (in && r.hit) {
      OcKey k;
      REQUIRE(map.grid().point_to_key(p, k));
      hits[k.pack()] += static_cast<double>(r.logodds);
    }
    if (r.ray == RayLayer::none) continue;
    double cut = max_range;
    if (r.ray == RayLayer::weak && (cut < 0 || layers.weak_range < cut)) cut = layers.weak_range;
    const Point3f end = cut >= 0 && range > cut ? truncate_ray(s.origin, p, cut) : p;
    if (compute_ray_keys(map.grid(), s.origin, end, ray))
      for (const OcKey& k : ray) (r.ray == RayLayer::strong ? strong : weak).insert(k.pack());
  }
  for (const auto& [k, sum] : hits) map.update(OcKey::unpack(k), static_cast<float>(sum));
  for (const std::uint64_t k : strong)
    if (!hits.count(k)) map.update(OcKey::unpack(k), layers.strong_miss);
  for (const std::uint64_t k : weak)
    if (!hits.count(k) && !strong.count(k)) map.update(OcKey::unpack(k), layers.weak_miss);
}

}  // namespace

TEST_CASE("insert_layered.two_layers_match_the_oracle") {
  test::Rng rng(7);
  std::vector<LayeredScan> scans;
  for (int i = 0; i < 4; ++i) scans.push_back(random_scan(rng, 0.1f * static_cast<float>(i)));
  const RayLayers layers{logodds(0.4), logodds(0.47), 3.0};
  for (const double max_range : {-1.0, 6.0, 2.0}) {
    CAPTURE(max_range);
    OccupancyMap<OcKey> want(0.05), map(0.05);
    LayeredScanInserter<OcKey> inserter(map, OctoMapModel{});
    for (const LayeredScan& s : scans) {
      oracle_insert(want, s, layers, max_range);
      const ScanStats st =
          inserter.insert_layered(s.origin, s.points, s.ratings, layers, max_range);
      CHECK(st.nonfinite == 1);
      CHECK(st.points == s.points.size());
      CHECK((max_range < 0 ? st.beyond_max_range == 0 : st.beyond_max_range >= 1));
      CHECK(st.occupied_voxels > 100);
      CHECK(st.free_voxels > 1000);
    }
    REQUIRE(want.num_voxels() > 20000);
    CHECK(same_voxels(map, want));
  }
}

TEST_CASE("insert_layered.one_layer_is_insert_rated") {
  // Hits with strong rays or none, no weak ray: the map ScanInserter::insert_rated makes.
  test::Rng rng(11);
  OccupancyMap<OcKey> rated(0.1), layered(0.1);
  const OctoMapModel model;
  ScanInserter<OcKey> a(rated, model);
  LayeredScanInserter<OcKey> b(layered, model);
  const RayLayers layers{model.miss_logodds(), logodds(0.45), 4.0};
  for (int i = 0; i < 3; ++i) {
    LayeredScan s = random_scan(rng, 0.2f * static_cast<float>(i));
    std::vector<EndpointRating> er;
    for (LayeredRating& r : s.ratings) {
      r.hit = true;
      if (r.ray == RayLayer::weak) r.ray = RayLayer::strong;
      er.push_back({r.logodds, r.ray == RayLayer::strong});
    }
    const ScanStats sa = a.insert_rated(s.origin, s.points, er, 5.0);
    const ScanStats sb = b.insert_layered(s.origin, s.points, s.ratings, layers, 5.0);
    CHECK(sa.occupied_voxels == sb.occupied_voxels);
    CHECK(sa.free_voxels == sb.free_voxels);
    CHECK(sa.beyond_max_range == sb.beyond_max_range);
  }
  CHECK(rated.num_voxels() > 10000);
  CHECK(same_voxels(rated, layered));
}

TEST_CASE("insert_layered.a_hit_is_never_freed_and_strong_beats_weak") {
  OccupancyMap<OcKey> map(0.1);
  LayeredScanInserter<OcKey> inserter(map, OctoMapModel{});
  const RayLayers layers{-0.4f, -0.1f, 10.0};
  // Two collinear points: the far one's strong ray crosses the near one's voxel (a hit of -0.7,
  // no free update); a weak ray along the same line adds nothing where the strong ray went.
  const std::vector<Point3f> pts{
      {1.05f, 0.05f, 0.05f}, {2.05f, 0.05f, 0.05f}, {3.05f, 0.05f, 0.05f}};
  const std::vector<LayeredRating> r{{-0.7f, true, RayLayer::none},
                                     {0.0f, false, RayLayer::strong},
                                     {0.0f, false, RayLayer::weak}};
  inserter.insert_layered(Point3f{0.05f, 0.05f, 0.05f}, pts, r, layers);
  auto at = [&](float x) {
    OcKey k;
    REQUIRE(map.grid().point_to_key(Point3f{x, 0.05f, 0.05f}, k));
    return map.logodds(k);
  };
  REQUIRE(at(1.05f));
  CHECK(*at(1.05f) == -0.7f);
  CHECK(*at(0.55f) == -0.4f);
  CHECK(*at(1.55f) == -0.4f);
  CHECK(*at(2.55f) == -0.1f);  // only the weak ray
  CHECK(*at(2.05f) == -0.1f);  // the strong ray's end voxel, not a hit: the weak ray frees it
  CHECK_FALSE(at(3.05f));      // the weak ray's own end voxel
}

TEST_CASE("insert_layered.bad_calls") {
  OccupancyMap<OcKey> map(0.1);
  LayeredScanInserter<OcKey> inserter(map, OctoMapModel{});
  const std::vector<Point3f> pts{{1, 0, 0}, {2, 0, 0}};
  CHECK_THROWS_AS(inserter.insert_layered(Point3f{}, pts, std::vector<LayeredRating>(1), {}),
                  std::invalid_argument);
  CHECK_THROWS_AS(inserter.insert_layered(Point3f{}, pts, std::vector<LayeredRating>(2), {}, 0.0),
                  std::invalid_argument);
  const ScanStats st = inserter.insert_layered(Point3f{std::nanf(""), 0, 0}, pts,
                                               std::vector<LayeredRating>(2), RayLayers{});
  CHECK_FALSE(st.origin_valid);
  CHECK(map.num_voxels() == 0);
  CHECK_THROWS_AS((LayeredScanInserter<OcKey>(map, OctoMapModel{}, 0)), std::invalid_argument);
}
