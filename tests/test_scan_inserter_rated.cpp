// ScanInserter::insert_rated (eq 15 scans) on large scans: threads, the dense and the hashed
// scratch, change detection on and off all give the map an oracle computes point by point
// (sums per voxel in point order, rays key by key with compute_ray_keys, updates voxel by voxel).

#include <doctest/doctest.h>

#include <map>
#include <random>
#include <set>
#include <vector>

#include <knnocc/insertion/scan_inserter.hpp>
#include <knnocc/raycast/dda.hpp>

#include "test_support.hpp"

using namespace knnocc;

using knnocc::test::voxel_values;

namespace {

struct RatedScan {
  Point3f origin;
  std::vector<Point3f> points;
  std::vector<EndpointRating> ratings;
};

// 20,000 points (well above the threaded collect threshold) in clusters, so many voxels hold
// several endpoints; a few NaN and far points.
RatedScan random_scan(test::Rng& rng, float ox) {
  std::uniform_real_distribution<float> u(-4.0f, 4.0f), small(-0.04f, 0.04f), l(-2.0f, 2.0f);
  RatedScan s;
  s.origin = {ox, 0.3f, 0.2f};
  while (s.points.size() < 20000) {
    const Point3f c{u(rng), u(rng), 0.5f * u(rng)};
    for (int j = 0; j < 4; ++j) {
      s.points.push_back({c.x + small(rng), c.y + small(rng), c.z + small(rng)});
      s.ratings.push_back({l(rng), rng() % 2 == 0});
    }
  }
  s.points[17] = {std::nanf(""), 0, 0};
  s.points[99] = {40.0f, 1.0f, 0.0f};  // beyond max range 6 (as are some box corners)
  return s;
}

// Returns how many points lie beyond max_range.
std::size_t oracle_insert(OccupancyMap<OcKey>& map, const RatedScan& s, double max_range,
                          float miss) {
  std::size_t beyond = 0;
  std::map<std::uint64_t, double> occupied;
  std::set<std::uint64_t> free;
  std::vector<OcKey> ray;
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    const Point3f& p = s.points[i];
    if (!std::isfinite(p.x)) continue;
    const bool in =
        detail::octomap_norm(p.x - s.origin.x, p.y - s.origin.y, p.z - s.origin.z) <= max_range;
    beyond += !in;
    const Point3f end = in ? p : truncate_ray(s.origin, p, max_range);
    if (in) {
      OcKey k;
      REQUIRE(map.grid().point_to_key(p, k));
      occupied[k.pack()] += static_cast<double>(s.ratings[i].logodds);
    }
    if (s.ratings[i].casts_ray && compute_ray_keys(map.grid(), s.origin, end, ray))
      for (const OcKey& k : ray) free.insert(k.pack());
  }
  for (const std::uint64_t k : free)
    if (!occupied.count(k)) map.update(OcKey::unpack(k), miss);
  for (const auto& [k, sum] : occupied) map.update(OcKey::unpack(k), static_cast<float>(sum));
  return beyond;
}

}  // namespace

TEST_CASE("insert_rated.threads_scratch_paths_and_change_detection_match_the_oracle") {
  test::Rng rng(31);
  std::vector<RatedScan> scans;
  for (int i = 0; i < 3; ++i) scans.push_back(random_scan(rng, 0.1f * static_cast<float>(i)));
  const double max_range = 6.0;
  const OctoMapModel model;  // miss_logodds() for the free voxels

  OccupancyMap<OcKey> want(0.05);
  std::vector<std::size_t> beyond;
  for (const RatedScan& s : scans)
    beyond.push_back(oracle_insert(want, s, max_range, model.miss_logodds()));
  CHECK(beyond[0] >= 1);
  const auto expected = voxel_values(want);
  REQUIRE(expected.size() > 50000);

  for (const unsigned threads : {1u, 3u})
    for (const bool hashed : {false, true})
      for (const bool changes : {false, true}) {
        CAPTURE(threads);
        CAPTURE(hashed);
        CAPTURE(changes);
        OccupancyMap<OcKey> map(0.05);
        if (changes) map.enable_change_detection(true);
        ScanInserter<OcKey> inserter(map, model, threads);
        if (hashed) inserter.set_scratch_limit(0);
        for (std::size_t i = 0; i < scans.size(); ++i) {
          const RatedScan& s = scans[i];
          const ScanStats st = inserter.insert_rated(s.origin, s.points, s.ratings, max_range);
          CHECK(st.nonfinite == 1);
          CHECK(st.beyond_max_range == beyond[i]);
        }
        CHECK(voxel_values(map) == expected);
        if (changes) {
          std::size_t recorded = 0;
          map.for_each_changed_key([&](const OcKey&, bool) { ++recorded; });
          CHECK(recorded > 0);
        }
      }
}

TEST_CASE("insert_rated.one_rating_per_point") {
  OccupancyMap<OcKey> map(0.1);
  ScanInserter<OcKey> inserter(map);
  const std::vector<Point3f> pts = {{1, 0, 0}, {2, 0, 0}};
  CHECK_THROWS_AS(inserter.insert_rated(Point3f{}, pts, std::vector<EndpointRating>(1)),
                  std::invalid_argument);
}
