// eval/heldout.hpp: the held-out scores against a brute force (views counted per id, rays sampled
// densely), and the folds.

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <set>
#include <stdexcept>
#include <utility>
#include <vector>

#include <knnocc/eval/heldout.hpp>

using namespace knnocc;

namespace {

// The key of a double point by floor(c / res), independent of Grid.
bool key_of(double res, double x, double y, double z, OcKey& k) {
  const double c[3] = {x, y, z};
  for (int a = 0; a < 3; ++a) {
    const double i = std::floor(c[a] / res) + double(OcKey::center);
    if (i < 0 || i >= double(OcKey::extent)) return false;
    k[a] = static_cast<std::uint16_t>(i);
  }
  return true;
}

// Does the segment seg (x0 y0 z0 x1 y1 z1) meet voxel k's box grown by eps (slab test)?
bool clips(double res, const OcKey& k, const std::array<double, 6>& seg, double eps) {
  double t0 = 0, t1 = 1;
  for (int a = 0; a < 3; ++a) {
    const double lo = (double(k[a]) - double(OcKey::center)) * res - eps, hi = lo + res + 2 * eps;
    const double o = seg[a], d = seg[a + 3] - seg[a];
    if (d == 0) {
      if (o < lo || o > hi) return false;
      continue;
    }
    double ta = (lo - o) / d, tb = (hi - o) / d;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return t0 <= t1;
}

// Random keyframes observing map points drawn from a pool (one position per id).
std::vector<eval::IdKeyframe> random_keyframes(std::mt19937_64& rng, std::size_t n) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Point3d> pool(40);
  for (Point3d& p : pool) p = {u(rng), u(rng), u(rng)};
  std::uniform_int_distribution<std::size_t> pick(0, pool.size() - 1);
  std::vector<eval::IdKeyframe> kfs(n);
  for (eval::IdKeyframe& kf : kfs) {
    kf.origin = {u(rng) * 1.5, u(rng) * 1.5, u(rng) * 1.5};
    for (int j = 0; j < 25; ++j) {
      const std::size_t id = pick(rng);
      kf.points.push_back(pool[id]);
      kf.ids.push_back(100 + id);
    }
  }
  return kfs;
}

}  // namespace

TEST_CASE("heldout: recall and seen-through voxels equal a brute force with dense ray samples") {
  std::mt19937_64 rng(2024);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_real_distribution<float> lo(-2.0f, 2.0f);
  std::size_t total_through = 0, total_recalled = 0, total_both = 0, clipped = 0;
  for (int trial = 0; trial < 12; ++trial) {
    const double res = trial % 2 ? 0.1 : 0.07;
    OccupancyMap<OcKey> map(res);
    for (int i = 0; i < 3000; ++i) {
      OcKey k;
      REQUIRE(key_of(res, u(rng), u(rng), u(rng), k));
      map.set(k, lo(rng));
    }
    const auto kfs = random_keyframes(rng, 7);
    const std::vector<std::size_t> heldout{1, 3, 4, 6};
    eval::HeldoutOptions opt;
    opt.min_views = 2 + trial % 2;
    opt.end_margin = trial % 3 == 2 ? 0.15 : 0.0;
    std::vector<OcKey> walked;
    const eval::HeldoutScore s = eval::score_heldout(map, kfs, heldout, opt, &walked);

    // Brute force: the keyframes that observe each id, then every ray sampled densely.
    std::map<std::uint64_t, std::set<std::size_t>> observers;
    std::map<std::uint64_t, Point3d> where;
    for (const std::size_t i : heldout)
      for (std::size_t j = 0; j < kfs[i].ids.size(); ++j) {
        observers[kfs[i].ids[j]].insert(i);
        where.emplace(kfs[i].ids[j], kfs[i].points[j]);
      }
    std::size_t points = 0, recalled = 0, rays = 0;
    for (const auto& e : observers) {
      if (e.second.size() < opt.min_views) continue;
      ++points;
      OcKey k;
      const Point3d& p = where.at(e.first);
      REQUIRE(key_of(res, p.x, p.y, p.z, k));
      recalled += map.is_occupied(k).value_or(false);
    }
    std::set<std::uint64_t> through;
    std::vector<std::array<double, 6>> segments;
    for (const std::size_t i : heldout) {
      const eval::IdKeyframe& kf = kfs[i];
      // the walk runs in float, as OctoMap's: sample the same float end points
      const double ox = float(kf.origin.x), oy = float(kf.origin.y), oz = float(kf.origin.z);
      for (std::size_t j = 0; j < kf.ids.size(); ++j) {
        if (observers.at(kf.ids[j]).size() < opt.min_views) continue;
        ++rays;
        // the walk's end: the point, or end_margin short of it
        Point3d e = kf.points[j];
        const double dx = e.x - kf.origin.x, dy = e.y - kf.origin.y, dz = e.z - kf.origin.z;
        const double full = std::sqrt(dx * dx + dy * dy + dz * dz);
        if (opt.end_margin > 0) {
          if (full <= opt.end_margin) continue;
          const double f = (full - opt.end_margin) / full;
          e = {kf.origin.x + f * dx, kf.origin.y + f * dy, kf.origin.z + f * dz};
        }
        const double ex = float(e.x), ey = float(e.y), ez = float(e.z);
        segments.push_back({ox, oy, oz, ex, ey, ez});
        OcKey end;
        REQUIRE(key_of(res, ex, ey, ez, end));
        const double len =
            std::sqrt((ex - ox) * (ex - ox) + (ey - oy) * (ey - oy) + (ez - oz) * (ez - oz));
        const int n = static_cast<int>(len / res * 2000) + 2;
        for (int t = 0; t <= n; ++t) {
          const double f = double(t) / n;
          OcKey k;
          if (!key_of(res, ox + f * (ex - ox), oy + f * (ey - oy), oz + f * (ez - oz), k)) break;
          if (k == end) break;  // the walk stops at the end voxel
          if (map.is_occupied(k).value_or(false)) through.insert(k.pack());
        }
      }
    }
    CHECK(s.points == points);
    CHECK(s.recalled == recalled);
    CHECK(s.rays == rays);
    // Every sampled voxel is walked; a walked voxel the samples missed is one the segment only
    // clips (within 1e-3 voxel of an edge or corner).
    std::set<std::uint64_t> walked_set;
    for (const OcKey& k : walked) walked_set.insert(k.pack());
    CHECK(s.seen_through == walked.size());
    for (const std::uint64_t k : through) CHECK(walked_set.count(k) == 1);
    for (const OcKey& k : walked) {
      if (through.count(k.pack())) continue;
      ++clipped;
      bool near = false;
      for (const auto& seg : segments) near = near || clips(res, k, seg, 1e-3 * res);
      CHECK_MESSAGE(near, "a walked voxel that no ray comes near");
    }
    CHECK(s.occupied == map.count_voxels().occupied);
    // Seen both ways: the walked voxels that hold a scored point.
    std::set<std::uint64_t> scored_voxels;
    for (const auto& e : observers) {
      OcKey k;
      const Point3d& p = where.at(e.first);
      if (e.second.size() >= opt.min_views && key_of(res, p.x, p.y, p.z, k))
        scored_voxels.insert(k.pack());
    }
    std::size_t both = 0;
    for (const std::uint64_t k : walked_set) both += scored_voxels.count(k);
    CHECK(s.seen_both == both);
    CHECK(s.seen_empty_only() == s.seen_through - both);
    total_both += both;
    // The walk behind the score, crossing by crossing: held-out keyframes' rays to scored points,
    // occupied voxels only, the same voxels and the same ray count.
    std::set<std::uint64_t> crossed;
    bool only_scored = true;
    const std::size_t walked_rays = eval::for_each_seen_through(
        map, kfs, heldout, eval::heldout_points(kfs, heldout), opt,
        [&](std::size_t i, std::size_t j, const OcKey& k) {
          only_scored = only_scored && std::count(heldout.begin(), heldout.end(), i) == 1 &&
                        observers.at(kfs[i].ids[j]).size() >= opt.min_views &&
                        map.is_occupied(k).value_or(false);
          crossed.insert(k.pack());
        });
    CHECK(only_scored);
    CHECK(walked_rays == rays);
    CHECK(crossed == walked_set);
    total_through += s.seen_through;
    total_recalled += s.recalled;
  }
  MESSAGE("12 maps: " << total_through << " seen-through voxels (" << clipped << " only clipped), "
                      << total_recalled << " recalled points");
  CHECK(clipped * 20 < total_through);
  CHECK(total_through > 100);
  CHECK(total_recalled > 20);
  CHECK(total_both > 0);
}

TEST_CASE("heldout: interleaved folds; every fold's map built from the others and summed") {
  std::mt19937_64 rng(9);
  const auto kfs = random_keyframes(rng, 11);
  for (std::size_t folds : {2u, 3u, 5u}) {
    std::vector<int> held(kfs.size(), 0);
    for (std::size_t f = 0; f < folds; ++f) {
      const auto in = eval::fold_indices(kfs.size(), folds, f, true);
      const auto out = eval::fold_indices(kfs.size(), folds, f, false);
      CHECK(in.size() + out.size() == kfs.size());
      for (const std::size_t i : in) {
        CHECK(i % folds == f);
        ++held[i];
      }
    }
    for (const int h : held) CHECK(h == 1);  // each keyframe held out exactly once
    // A builder that marks the training points occupied: the sum equals per-fold scoring.
    auto build = [&](const std::vector<std::size_t>& train) {
      OccupancyMap<OcKey> m(0.1);
      for (const std::size_t i : train) {
        for (std::size_t j = 0; j < kfs[i].points.size(); ++j) {
          OcKey k;
          REQUIRE(m.grid().point_to_key(kfs[i].points[j], k));
          m.set(k, 1.0f);
        }
      }
      return m;
    };
    eval::HeldoutOptions opt;
    opt.folds = folds;
    const eval::HeldoutScore total = eval::evaluate_heldout(kfs, opt, build);
    eval::HeldoutScore sum;
    for (std::size_t f = 0; f < folds; ++f)
      sum += eval::score_heldout(build(eval::fold_indices(kfs.size(), folds, f, false)), kfs,
                                 eval::fold_indices(kfs.size(), folds, f, true), opt);
    CHECK(total.points == sum.points);
    CHECK(total.recalled == sum.recalled);
    CHECK(total.seen_through == sum.seen_through);
    CHECK(total.seen_both == sum.seen_both);
    CHECK(total.points > 0);
    CHECK(total.recall() > 0.9);  // the pool is small: training keyframes saw nearly every point
    // Several options on one map per fold: each score equals that option's own evaluation.
    eval::HeldoutOptions margin = opt;
    margin.end_margin = 0.2;
    margin.min_views = 3;
    const auto both =
        eval::evaluate_heldout(kfs, std::vector<eval::HeldoutOptions>{opt, margin}, build);
    REQUIRE(both.size() == 2);
    const eval::HeldoutScore alone = eval::evaluate_heldout(kfs, margin, build);
    CHECK(both[0].seen_through == total.seen_through);
    CHECK(both[0].recalled == total.recalled);
    CHECK(both[1].points == alone.points);
    CHECK(both[1].recalled == alone.recalled);
    CHECK(both[1].seen_through == alone.seen_through);
    CHECK(both[1].seen_both == alone.seen_both);
    CHECK(both[1].rays < both[0].rays);  // min_views 3 scores fewer points
    eval::HeldoutOptions other_folds = opt;
    other_folds.folds = folds + 1;
    CHECK_THROWS_AS(
        eval::evaluate_heldout(kfs, std::vector<eval::HeldoutOptions>{opt, other_folds}, build),
        std::invalid_argument);
  }
  eval::HeldoutOptions bad;
  bad.folds = 1;
  CHECK_THROWS_AS(
      eval::evaluate_heldout(
          kfs, bad, [](const std::vector<std::size_t>&) { return OccupancyMap<OcKey>(0.1); }),
      std::invalid_argument);
}

TEST_CASE("heldout: the floor equals the fewest seen-through voxels of every map, enumerated") {
  // Small scenes with coarse voxels, so that held-out rays cross voxels holding held-out points.
  // Every pair of fold maps over the voxels holding scored points is scored; the floor must be
  // the least seen-through count among the pairs that recall at least r points, for every r.
  // In odd scenes each keyframe sees a point a little off its position (a point's rays may cross
  // its own voxel); every third scene stops the rays short of their points.
  const double res = 1.0;  // eight voxels hold the pool: several points share one
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int scenes = 0, with_crossed = 0;
  while (scenes < 12) {
    std::vector<Point3d> pool(8);
    for (Point3d& p : pool) p = {u(rng), u(rng), u(rng)};
    std::vector<eval::IdKeyframe> kfs(4);
    for (eval::IdKeyframe& kf : kfs) {
      kf.origin = {u(rng) * 3, u(rng) * 3, u(rng) * 3};
      for (std::size_t id = 0; id < pool.size(); ++id)
        if (rng() % 3 != 0) {
          const Point3d& p = pool[id];
          const double j = scenes % 2 ? 0.1 : 0.0;  // odd scenes: off the point's position
          kf.points.push_back({p.x + j * u(rng), p.y + j * u(rng), p.z + j * u(rng)});
          kf.ids.push_back(id);
        }
    }
    eval::HeldoutOptions opt;
    opt.folds = 2;
    opt.end_margin = scenes % 3 == 2 ? 0.4 : 0.0;
    const Grid<OcKey> grid(res);
    std::vector<OcKey> voxels;  // every voxel holding a scored point of either fold
    for (std::size_t f = 0; f < 2; ++f)
      for (const auto& e : eval::heldout_points(kfs, eval::fold_indices(4, 2, f, true))) {
        OcKey k;
        if (e.second.views < opt.min_views || !grid.point_to_key(e.second.position, k)) continue;
        if (std::find(voxels.begin(), voxels.end(), k) == voxels.end()) voxels.push_back(k);
      }
    if (voxels.empty() || voxels.size() > 6) continue;
    ++scenes;
    const eval::HeldoutFloor floor = eval::evaluate_heldout_floor(grid, kfs, opt);
    with_crossed += !floor.crossed.empty();
    const std::size_t n = voxels.size();
    std::map<std::size_t, std::size_t> fewest;  // recalled -> least seen-through
    std::size_t points = 0;
    for (std::size_t a = 0; a < (1u << n); ++a)
      for (std::size_t b = 0; b < (1u << n); ++b) {
        eval::HeldoutScore sum;
        for (std::size_t f = 0; f < 2; ++f) {
          OccupancyMap<OcKey> map(res);
          for (std::size_t v = 0; v < n; ++v)
            if (((f == 0 ? a : b) >> v) & 1u) map.set(voxels[v], 1.0f);
          sum += eval::score_heldout(map, kfs, eval::fold_indices(4, 2, f, true), opt);
        }
        points = sum.points;
        auto it = fewest.find(sum.recalled);
        if (it == fewest.end() || sum.seen_through < it->second)
          fewest[sum.recalled] = sum.seen_through;
      }
    CAPTURE(scenes);
    CHECK(floor.points == points);
    for (std::size_t r = 0; r <= points + 1; ++r) {
      std::optional<std::size_t> want;
      for (const auto& [recalled, st] : fewest)
        if (recalled >= r && (!want || st < *want)) want = st;
      CAPTURE(r);
      CHECK(floor.fewest_seen_through(r) == want);
    }
  }
  CHECK(with_crossed >= 4);  // the scenes do test crossed voxels
}
