// eval/multiview.hpp: map quality without ground truth, against brute-force counts over every
// pair of voxels.

#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <set>
#include <vector>

#include <knnocc/eval/multiview.hpp>

using namespace knnocc;

namespace {

struct Voxel {
  OcKey k;
  float v;
};

std::vector<Voxel> voxels_of(const OccupancyMap<OcKey>& m) {
  std::vector<Voxel> out;
  m.for_each_voxel([&](const OcKey& k, float v) { out.push_back({k, v}); });
  return out;
}

}  // namespace

TEST_CASE("multiview: views count each id once per keyframe; seen-once fraction") {
  eval::MapPointViews v;
  v.add_keyframe({{0, 0, 0}, {1, 0, 0}, {1, 0, 0}}, {7, 8, 8});  // 8 twice in one keyframe
  v.add_keyframe({{5, 5, 5}, {2, 0, 0}}, {7, 9});                // 7 moved: first position kept
  v.add_keyframe({{0, 0, 0}}, {7});
  REQUIRE(v.size() == 3);
  CHECK(v.keyframes() == 3);
  CHECK(v.points().at(7).keyframes == 3);
  CHECK(v.points().at(7).position.x == 0.0);
  CHECK(v.points().at(8).keyframes == 1);
  CHECK(v.seen_once() == 2);
  CHECK(v.seen_once_fraction() == doctest::Approx(2.0 / 3.0));
  CHECK(v.count_at_least(3) == 1);
  CHECK(v.median_views() == 1.0);
}

TEST_CASE("multiview: the proxies equal brute-force counts on random maps") {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.6, 0.6);
  std::uniform_real_distribution<float> lo(-2.0f, 2.0f);
  for (int trial = 0; trial < 6; ++trial) {
    const double res = trial % 2 ? 0.1 : 0.07;
    OccupancyMap<OcKey> map(res), ref(res);
    for (int i = 0; i < 400; ++i) {
      OcKey k;
      REQUIRE(map.grid().coord_to_key(u(rng), u(rng), u(rng), k));
      map.set(k, lo(rng));
      REQUIRE(ref.grid().coord_to_key(u(rng), u(rng), u(rng), k));
      ref.set(k, lo(rng));
    }
    eval::MapPointViews views;
    for (int kf = 0; kf < 8; ++kf) {
      std::vector<Point3d> pts;
      std::vector<std::uint64_t> ids;
      for (std::uint64_t id = 0; id < 150; ++id)
        if (rng() % 3 == 0) {
          std::mt19937 at(static_cast<unsigned>(id));  // a fixed position per id
          std::uniform_real_distribution<double> w(-0.6, 0.6);
          pts.push_back({w(at), w(at), w(at)});
          ids.push_back(id);
        }
      views.add_keyframe(pts, ids);
    }
    eval::MultiviewOptions opt;
    opt.far = trial < 3 ? 0.3 : 0.15;
    const eval::MultiviewMetrics m = eval::evaluate_multiview(map, views, &ref, opt);

    // Brute force.
    const auto& g = map.grid();
    std::set<OcKey> mv;
    for (const auto& [id, e] : views.points())
      if (e.keyframes >= opt.min_views) {
        OcKey k;
        REQUIRE(g.point_to_key(e.position, k));
        mv.insert(k);
      }
    const auto all = voxels_of(map);
    auto occ = [&](const OccupancyMap<OcKey>& mp, const OcKey& k) {
      const auto v = mp.logodds(k);
      return v && mp.is_occupied(*v);
    };
    std::size_t occupied = 0, isolated = 0, far = 0, kept = 0, lost = 0, free_mv = 0;
    for (const Voxel& a : all) {
      if (!map.is_occupied(a.v)) continue;
      ++occupied;
      bool neighbour = false;
      for (const Voxel& b : all) {
        if (!map.is_occupied(b.v) || b.k == a.k) continue;
        int d = 0;
        for (int i = 0; i < 3; ++i) d = std::max(d, std::abs(int(a.k[i]) - int(b.k[i])));
        neighbour = neighbour || d == 1;
      }
      isolated += !neighbour;
      bool near = false;
      for (const OcKey& k : mv) {
        double d2 = 0;
        for (int i = 0; i < 3; ++i) {
          const double d = g.index_to_coord(a.k[i]) - g.index_to_coord(k[i]);
          d2 += d * d;
        }
        near = near || d2 <= opt.far * opt.far * (1 + 1e-9);
      }
      far += !near;
    }
    for (const OcKey& k : mv) {
      const auto v = map.logodds(k);
      free_mv += v && !map.is_occupied(*v);
      if (occ(ref, k)) {
        ++kept;
        lost += !occ(map, k);
      }
    }
    CAPTURE(trial);
    CHECK(m.multiview == mv.size());
    CHECK(m.occupied == occupied);
    CHECK(m.isolated == isolated);
    CHECK(m.far == far);
    CHECK(m.reference_kept == kept);
    CHECK(m.lost == lost);
    CHECK(m.free_multiview == free_mv);
    CHECK(mv.size() > 10);  // the random case exercises every count
    CHECK(isolated > 0);
    CHECK(far > 0);
    CHECK(occupied > isolated);
  }
}

TEST_CASE("multiview: without a reference map, lost and reference_kept stay 0") {
  OccupancyMap<OcKey> map(0.1);
  eval::MapPointViews views;
  for (int i = 0; i < 3; ++i) views.add_keyframe({{0.05, 0.05, 0.05}}, {1});
  const auto m = eval::evaluate_multiview(map, views, nullptr);
  CHECK(m.multiview == 1);
  CHECK(m.lost == 0);
  CHECK(m.reference_kept == 0);
  CHECK(m.free_multiview == 0);  // unknown is not free
}
