// eval/confusion.hpp and eval/reference_points.hpp: the authors' counting against an exhaustive
// search over every one-to-one matching of small random maps, hand-made cases, and precision and
// recall against reference points by brute force.

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <unordered_map>
#include <utility>
#include <vector>

#include <knnocc/eval/confusion.hpp>
#include <knnocc/eval/reference_points.hpp>

using namespace knnocc;

namespace {

OcKey key_at(int x, int y, int z) {
  return OcKey(static_cast<std::uint16_t>(OcKey::center + x),
               static_cast<std::uint16_t>(OcKey::center + y),
               static_cast<std::uint16_t>(OcKey::center + z));
}

bool within_one(const OcKey& a, const OcKey& b) {
  for (int i = 0; i < 3; ++i)
    if (std::abs(int(a[i]) - int(b[i])) > 1) return false;
  return true;
}

// The counting from its definition: every one-to-one matching of occupied map cells (known in
// the reference) to occupied reference cells within +-1 voxel tried, the best by (TP, then FN
// candidates covered) kept.
eval::ConfusionCounts brute_force(const OccupancyMap<OcKey>& map, const OccupancyMap<OcKey>& ref,
                                  float threshold = 0.0f) {
  std::vector<OcKey> left, right, cand;
  eval::ConfusionCounts c;
  map.for_each_voxel([&](const OcKey& k, float v) {
    const auto r = ref.logodds(k);
    if (!r) return;
    if (v >= threshold)
      left.push_back(k);
    else if (ref.is_occupied(*r))
      cand.push_back(k);
    else
      ++c.tn;
  });
  ref.for_each_voxel([&](const OcKey& k, float v) {
    if (ref.is_occupied(v)) right.push_back(k);
  });
  std::vector<char> is_cand(right.size(), 0);
  for (std::size_t j = 0; j < right.size(); ++j)
    is_cand[j] = std::find(cand.begin(), cand.end(), right[j]) != cand.end();
  std::map<std::pair<std::size_t, std::uint64_t>, std::pair<int, int>> memo;
  // best (tp, covered candidates) for left[i..] with the right cells in `used` taken
  auto best = [&](auto&& self, std::size_t i, std::uint64_t used) -> std::pair<int, int> {
    if (i == left.size()) return {0, 0};
    const auto key = std::make_pair(i, used);
    if (const auto it = memo.find(key); it != memo.end()) return it->second;
    std::pair<int, int> b = self(self, i + 1, used);  // left[i] unmatched
    for (std::size_t j = 0; j < right.size(); ++j) {
      if ((used >> j) & 1u || !within_one(left[i], right[j])) continue;
      auto r = self(self, i + 1, used | (std::uint64_t{1} << j));
      r.first += 1;
      r.second += is_cand[j];
      b = std::max(b, r);
    }
    return memo[key] = b;
  };
  REQUIRE(right.size() <= 64);
  const auto b = best(best, 0, 0);
  c.tp = static_cast<std::size_t>(b.first);
  c.fp = left.size() - c.tp;
  c.fn = cand.size() - static_cast<std::size_t>(b.second);
  return c;
}

void check_equal(const eval::ConfusionCounts& a, const eval::ConfusionCounts& b) {
  CHECK(a.tp == b.tp);
  CHECK(a.fp == b.fp);
  CHECK(a.tn == b.tn);
  CHECK(a.fn == b.fn);
}

}  // namespace

TEST_CASE("confusion: F1 and MCC from their definitions") {
  eval::ConfusionCounts c;
  c.tp = 30;
  c.fp = 10;
  c.tn = 50;
  c.fn = 20;
  CHECK(c.f1() == doctest::Approx(60.0 / 90.0));
  CHECK(c.precision() == doctest::Approx(0.75));
  CHECK(c.recall() == doctest::Approx(0.6));
  CHECK(c.mcc() == doctest::Approx((30.0 * 50 - 10.0 * 20) / std::sqrt(40.0 * 50 * 60 * 70)));
  CHECK(eval::ConfusionCounts{}.f1() == 0.0);
  CHECK(eval::ConfusionCounts{}.mcc() == 0.0);
}

TEST_CASE("confusion: the counting equals an exhaustive search over matchings on random maps") {
  std::mt19937_64 rng(33);
  std::uniform_int_distribution<int> x(0, 4), y(0, 3), z(0, 1);
  std::uniform_real_distribution<float> v(-2.0f, 2.0f);
  std::size_t tp = 0, fn = 0, matched_maps = 0;
  for (int trial = 0; trial < 300; ++trial) {
    OccupancyMap<OcKey> map(0.1), ref(0.1);
    const int cells = 4 + trial % 12;
    for (int i = 0; i < cells; ++i) map.set(key_at(x(rng), y(rng), z(rng)), v(rng));
    for (int i = 0; i < 20; ++i) ref.set(key_at(x(rng), y(rng), z(rng)), v(rng));
    const eval::ConfusionCounts got = eval::count_confusion(map, eval::MapVoxels<OcKey>(ref));
    const eval::ConfusionCounts want = brute_force(map, ref);
    check_equal(got, want);
    // Several thresholds in one call: each as by itself.
    const std::vector<float> thresholds{0.7f, -0.5f, 0.0f, 1.5f};
    const auto several = eval::count_confusion(map, eval::MapVoxels<OcKey>(ref), thresholds);
    REQUIRE(several.size() == thresholds.size());
    for (std::size_t t = 0; t < thresholds.size(); ++t)
      check_equal(several[t], brute_force(map, ref, thresholds[t]));
    tp += got.tp;
    fn += got.fn;
    matched_maps += got.tp > 1;
  }
  MESSAGE("300 random maps: " << tp << " TP, " << fn << " FN");
  CHECK(tp > 300);  // the maps exercise the matching, not only the empty case
  CHECK(matched_maps > 50);
}

TEST_CASE("confusion: one voxel of tolerance, each reference cell granted once") {
  OccupancyMap<OcKey> map(0.1), ref(0.1);
  // Reference: a wall x = 0, y 0..4 (occupied), free in front of it (x = -1, -2).
  for (int yy = 0; yy < 5; ++yy) {
    ref.set(key_at(0, yy, 0), 2.0f);
    ref.set(key_at(-1, yy, 0), -1.0f);
    ref.set(key_at(-2, yy, 0), -1.0f);
  }
  SUBCASE("a map one voxel in front of the wall: all TP") {
    for (int yy = 0; yy < 5; ++yy) map.set(key_at(-1, yy, 0), 1.0f);
    const auto c = eval::count_confusion(map, eval::MapVoxels<OcKey>(ref));
    CHECK(c.tp == 5);
    CHECK(c.fp == 0);
  }
  SUBCASE("two layers on a one-layer wall: half of them FP") {
    for (int yy = 0; yy < 5; ++yy) {
      map.set(key_at(0, yy, 0), 1.0f);
      map.set(key_at(-1, yy, 0), 1.0f);
    }
    const auto c = eval::count_confusion(map, eval::MapVoxels<OcKey>(ref));
    CHECK(c.tp == 5);
    CHECK(c.fp == 5);
  }
  SUBCASE("a wall cell carved: FN unless an occupied neighbour took it") {
    map.set(key_at(0, 0, 0), -1.0f);  // carved, nothing occupied near: FN
    map.set(key_at(0, 4, 0), -1.0f);  // carved, but the surface is one voxel off: matched
    map.set(key_at(-1, 4, 0), 1.0f);
    map.set(key_at(-2, 2, 0), -1.0f);  // free in both: TN
    const auto c = eval::count_confusion(map, eval::MapVoxels<OcKey>(ref));
    CHECK(c.tp == 1);
    CHECK(c.fn == 1);
    CHECK(c.tn == 1);
    CHECK(c.fp == 0);
  }
  SUBCASE("cells unknown in the reference are not counted; a threshold re-labels the map") {
    map.set(key_at(5, 5, 5), 1.0f);  // unknown in the reference
    map.set(key_at(-2, 0, 0), 0.5f);
    auto c = eval::count_confusion(map, eval::MapVoxels<OcKey>(ref));
    CHECK(c.fp == 1);
    CHECK(c.tp + c.tn + c.fn == 0);
    eval::ConfusionOptions o;
    o.threshold = 0.6f;
    c = eval::count_confusion(map, eval::MapVoxels<OcKey>(ref), o);
    CHECK(c.fp == 0);
    CHECK(c.tn == 1);
  }
}

TEST_CASE("confusion: shapes voxelised: surface and inside occupied, the ground band unknown") {
  eval::Reference ref;
  ref.has_ground = true;
  ref.ground_z = 0.0;
  ref.cuboids.push_back({{0.25, 0.25, 0.0}, {0.75, 0.75, 0.75}});
  const Grid<OcKey> g(0.1);
  const eval::ShapeVoxels<OcKey> shapes(ref, g);
  OcKey k;
  auto at = [&](double xx, double yy, double zz) {
    REQUIRE(g.coord_to_key(xx, yy, zz, k));
    return k;
  };
  CHECK(shapes.occupied(at(0.45, 0.45, 0.45)));        // inside
  CHECK(shapes.occupied(at(0.25, 0.45, 0.45)));        // on a face
  CHECK_FALSE(shapes.occupied(at(0.05, 0.45, 0.45)));  // beside it
  CHECK(shapes.known(at(0.05, 0.45, 0.45)));
  CHECK_FALSE(shapes.known(at(2.0, 2.0, 0.05)));  // the ground band (centres below 0.3 m)
  CHECK_FALSE(shapes.known(at(2.0, 2.0, 0.25)));
  CHECK_FALSE(shapes.known(at(2.0, 2.0, -0.35)));  // under the ground
  CHECK(shapes.known(at(2.0, 2.0, 0.35)));
  CHECK_FALSE(shapes.occupied(at(2.0, 2.0, 0.35)));
  // Against a brute force: a voxel is occupied iff a sample of its closed box lies in the solid.
  for (int x = -2; x < 10; ++x)
    for (int y = -2; y < 10; ++y)
      for (int z = 3; z < 10; ++z) {
        const OcKey key = at((x + 0.5) * 0.1, (y + 0.5) * 0.1, (z + 0.5) * 0.1);
        bool inside = false;
        for (int s = 0; s <= 4 && !inside; ++s)
          for (int t = 0; t <= 4 && !inside; ++t)
            for (int u = 0; u <= 4 && !inside; ++u)
              inside =
                  ref.contains({(x + s / 4.0) * 0.1, (y + t / 4.0) * 0.1, (z + u / 4.0) * 0.1});
        CHECK(shapes.occupied(key) == inside);
      }
}

TEST_CASE("reference points: precision and recall equal a brute-force distance count") {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  std::uniform_real_distribution<float> v(-2.0f, 2.0f);
  for (int trial = 0; trial < 20; ++trial) {
    const double res = trial % 2 ? 0.1 : 0.05;
    OccupancyMap<OcKey> map(res);
    std::vector<Point3d> pts, seen_pts;
    for (int i = 0; i < 60; ++i) {
      OcKey k;
      REQUIRE(map.grid().coord_to_key(u(rng), u(rng), u(rng), k));
      map.set(k, v(rng));
      pts.push_back({u(rng), u(rng), u(rng)});
      if (i % 2) seen_pts.push_back({u(rng), u(rng), u(rng)});
    }
    const eval::PointVoxels<OcKey> ref(pts, map.grid());
    std::unordered_set<OcKey, KeyHash> seen;
    for (const Point3d& p : seen_pts) {
      OcKey k;
      REQUIRE(map.grid().point_to_key(p, k));
      seen.insert(k);
    }
    const eval::PointCoverage c = eval::point_coverage(map, ref, &seen);
    // Brute force over all pairs, by the keys' Chebyshev distance.
    std::vector<OcKey> occupied, cells(ref.cells().begin(), ref.cells().end());
    map.for_each_voxel([&](const OcKey& k, float lo) {
      if (map.is_occupied(lo)) occupied.push_back(k);
    });
    std::size_t near = 0, visible = 0, covered = 0;
    for (const OcKey& o : occupied)
      near +=
          std::any_of(cells.begin(), cells.end(), [&](const OcKey& r) { return within_one(o, r); });
    for (const OcKey& r : cells) {
      if (!std::any_of(seen.begin(), seen.end(), [&](const OcKey& s) { return within_one(r, s); }))
        continue;
      ++visible;
      covered += std::any_of(occupied.begin(), occupied.end(),
                             [&](const OcKey& o) { return within_one(o, r); });
    }
    CHECK(c.occupied == occupied.size());
    CHECK(c.near == near);
    CHECK(c.visible == visible);
    CHECK(c.covered == covered);
    CHECK(eval::point_coverage(map, ref, nullptr).visible == cells.size());
    // Known: the points' bounding box grown by one voxel.
    OcKey corner;
    REQUIRE(map.grid().coord_to_key(0.9, 0.9, 0.9, corner));
    CHECK_FALSE(ref.known(corner));
  }
}
