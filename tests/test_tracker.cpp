// KnnTracker (knn/tracker.hpp) against brute force: random sequences, edge cases, rounding, the
// paper's Alg. 1 policy, ties far from the origin.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <unordered_map>
#include <vector>

#include <knnocc/io/sequence.hpp>
#include <knnocc/knn/tracker.hpp>

#include "knn_oracle.hpp"
#include "test_support.hpp"

using knnocc::ChangeSet;
using knnocc::Point3d;
using knnocc::test::brute_force;
using knnocc::test::Cloud;
using knnocc::test::expect_matches;
using knnocc::test::Truth;

namespace {

// Random change sets mixing the hard cases: duplicates, tight clusters, far outliers, moves.
class Scenario {
 public:
  explicit Scenario(std::uint64_t seed) : rng_(seed) {}

  ChangeSet next(const Cloud& cloud, std::size_t adds, std::size_t removes, std::size_t moves) {
    ChangeSet cs;
    std::vector<std::uint64_t> ids;
    for (const auto& [id, p] : cloud) ids.push_back(id);
    std::shuffle(ids.begin(), ids.end(), rng_);
    std::size_t used = 0;
    for (std::size_t i = 0; i < removes && used < ids.size(); ++i)
      cs.removed.push_back(ids[used++]);
    for (std::size_t i = 0; i < moves && used < ids.size(); ++i)
      cs.moved.push_back({ids[used++], point(cloud)});
    for (std::size_t i = 0; i < adds; ++i) cs.added.push_back({next_id_++, point(cloud)});
    return cs;
  }

 private:
  Point3d point(const Cloud& cloud) {
    const double kind = u_(rng_);
    if (kind < 0.1 && !cloud.empty()) {  // exact duplicate of an existing point
      auto it = cloud.begin();
      std::advance(it, static_cast<long>(u_(rng_) * static_cast<double>(cloud.size())) %
                           static_cast<long>(cloud.size()));
      return it->second;
    }
    if (kind < 0.4) {  // tight cluster around one of three centres
      const int c = static_cast<int>(u_(rng_) * 3);
      return {c * 1.0 + 0.01 * g_(rng_), 0.5 + 0.01 * g_(rng_), -0.3 * c + 0.01 * g_(rng_)};
    }
    if (kind < 0.45) return {20 + 5 * u_(rng_), -30 * u_(rng_), 10 * u_(rng_)};  // outlier
    if (kind < 0.55)  // on a grid: many equal distances (ties decided by id)
      return {0.1 * std::floor(u_(rng_) * 10), 0.1 * std::floor(u_(rng_) * 10), 2.0};
    return {3 * u_(rng_) - 1.5, 3 * u_(rng_) - 1.5, 3 * u_(rng_) - 1.5};
  }

  knnocc::test::Rng rng_;
  std::uniform_real_distribution<double> u_{0.0, 1.0};
  std::normal_distribution<double> g_{0.0, 1.0};
  std::uint64_t next_id_ = 1000;
};

void apply_to(Cloud& cloud, const ChangeSet& cs) {
  for (auto id : cs.removed) cloud.erase(id);
  for (const auto& m : cs.moved) cloud[m.id] = m.p;
  for (const auto& a : cs.added) cloud[a.id] = a.p;
}

}  // namespace

TEST_CASE("knn_tracker.random_sequences_match_brute_force") {
  for (const std::size_t k : {1u, 2u, 3u, 5u, 8u, 16u}) {
    CAPTURE(k);
    knnocc::TrackerParams params;
    params.k = k;
    params.s_limit = k % 2 ? 0.5 : std::numeric_limits<double>::infinity();
    params.compact_min_dead = 50;           // exercise compaction often
    params.rebuild_min = 8 + 40 * (k % 3);  // and static-tree rebuilds, at varying sizes
    knnocc::KnnTracker<> tracker(params);
    Cloud cloud;
    Scenario scenario(100 + k);
    for (int step = 0; step < 25; ++step) {
      CAPTURE(step);
      const std::size_t adds = step == 0 ? 3 : (step < 5 ? 60 : 25);
      const std::size_t removes = step < 3 ? 0 : 20, moves = step < 3 ? 0 : 6;
      const ChangeSet cs = scenario.next(cloud, adds, removes, moves);
      const auto up = tracker.apply(cs);
      CHECK(up.added == cs.added.size());
      CHECK(up.removed == cs.removed.size());
      CHECK(up.moved == cs.moved.size());
      apply_to(cloud, cs);
      expect_matches(tracker, cloud);
    }
  }
}

TEST_CASE("knn_tracker.defined_edge_cases") {
  knnocc::TrackerParams params;
  params.k = 4;
  knnocc::KnnTracker<> tr(params);
  ChangeSet cs;
  SUBCASE("k larger than the cloud: no s, empty distribution") {
    for (std::uint64_t i = 0; i < 4; ++i) cs.added.push_back({i, {double(i), 0, 0}});
    tr.apply(cs);
    CHECK(std::isnan(tr.s(0)));
    CHECK(tr.N() == 0);
    CHECK(tr.mu() == 0.0);
    CHECK(tr.sigma() == 0.0);
    // One more point: everyone now has k neighbours and joins as new (section 4.3).
    ChangeSet more;
    more.added.push_back({9, {4, 0, 0}});
    tr.apply(more);
    CHECK(tr.N() == 5);
    CHECK(tr.s(0) == doctest::Approx((1 + 2 + 3 + 4) / 4.0));
  }
  SUBCASE("all points identical: s = 0, sigma = 0") {
    for (std::uint64_t i = 0; i < 10; ++i) cs.added.push_back({i, {1, 2, 3}});
    tr.apply(cs);
    CHECK(tr.s(5) == 0.0);
    CHECK(tr.N() == 10);
    CHECK(tr.sigma() == 0.0);
    CHECK(tr.neighbours(5) == std::vector<std::uint64_t>{0, 1, 2, 3});  // ties by id
  }
  SUBCASE("non-finite positions are skipped and counted") {
    cs.added.push_back({1, {std::nan(""), 0, 0}});
    cs.added.push_back({2, {0, INFINITY, 0}});
    cs.added.push_back({3, {0, 0, 0}});
    const auto up = tr.apply(cs);
    CHECK(up.skipped_nonfinite == 2);
    CHECK(up.added == 1);
    CHECK(tr.size() == 1);
    CHECK_FALSE(tr.contains(1));
  }
  SUBCASE("caller errors are refused before anything changes") {
    cs.added.push_back({1, {0, 0, 0}});
    tr.apply(cs);
    ChangeSet bad;
    bad.removed.push_back(42);
    CHECK_THROWS_AS(tr.apply(bad), std::invalid_argument);
    ChangeSet dup;
    dup.added.push_back({1, {1, 1, 1}});
    CHECK_THROWS_AS(tr.apply(dup), std::invalid_argument);
    CHECK(tr.size() == 1);
    CHECK(tr.position(1).x == 0.0);
  }
  SUBCASE("removing everything empties the distribution exactly") {
    for (std::uint64_t i = 0; i < 30; ++i) cs.added.push_back({i, {0.1 * double(i), 0, 0}});
    tr.apply(cs);
    CHECK(tr.N() == 30);
    ChangeSet all;
    for (std::uint64_t i = 0; i < 30; ++i) all.removed.push_back(i);
    tr.apply(all);
    CHECK(tr.size() == 0);
    CHECK(tr.N() == 0);
    CHECK(tr.mu() == 0.0);
  }
  CHECK_THROWS_AS(knnocc::KnnTracker<>(knnocc::TrackerParams{0}), std::invalid_argument);
}

TEST_CASE("knn_tracker.erasing_an_outlier_keeps_sigma_exact") {
  // Erasing values far from the rest cancels nearly all of S (eq 10): the tracker notices and
  // recomputes the distribution from the stored s values.
  knnocc::TrackerParams params;
  params.k = 3;
  knnocc::KnnTracker<> tr(params);
  Cloud cloud;
  ChangeSet cs;
  knnocc::test::Rng rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  for (std::uint64_t i = 0; i < 100; ++i) cs.added.push_back({i, {u(rng), u(rng), u(rng)}});
  cs.added.push_back({500, {1e8, 0, 0}});  // its s is ~1e8: S is almost all its own
  tr.apply(cs);
  apply_to(cloud, cs);
  ChangeSet out;
  out.removed = {500};
  tr.apply(out);
  apply_to(cloud, out);
  expect_matches(tr, cloud);
}

TEST_CASE("knn_tracker.bad_parameters_are_refused_up_front") {
  knnocc::TrackerParams params;
  CHECK_THROWS_AS(knnocc::KnnTracker<knnocc::PaperAnnulus>(params, knnocc::PaperAnnulus{0.0, 2.0}),
                  std::invalid_argument);
  CHECK_THROWS_AS(knnocc::KnnTracker<knnocc::PaperAnnulus>(params, knnocc::PaperAnnulus{1e-9, 2.0}),
                  std::invalid_argument);  // would take 2e9 radius queries per point
  params.rebuild_min = 0;
  CHECK_THROWS_AS(knnocc::KnnTracker<>{params}, std::invalid_argument);
}

TEST_CASE("knn_tracker.paper_annulus_misses_affected_points") {
  // Two dense clusters 4 m apart and a lone point between them whose k-NN reach into the left
  // cluster. Points added to the left cluster change the lone point's k-NN, but Alg. 1's annulus
  // stops as soon as one ring of the cluster is unchanged, long before it reaches 1.9 m.
  knnocc::TrackerParams params;
  params.k = 4;
  knnocc::KnnTracker<> exact(params);
  knnocc::KnnTracker<knnocc::PaperAnnulus> paper(params, knnocc::PaperAnnulus{0.05, 3.0});
  knnocc::test::Rng rng(5);
  std::normal_distribution<double> g(0.0, 0.05);
  ChangeSet cs;
  std::uint64_t id = 0;
  for (int i = 0; i < 200; ++i) cs.added.push_back({id++, {g(rng), g(rng), g(rng)}});
  for (int i = 0; i < 200; ++i) cs.added.push_back({id++, {4 + g(rng), g(rng), g(rng)}});
  cs.added.push_back({id++, {2.0, 0.0, 0.0}});
  exact.apply(cs);
  paper.apply(cs);
  Cloud cloud;
  apply_to(cloud, cs);
  std::size_t missed_total = 0;
  for (int step = 0; step < 5; ++step) {
    ChangeSet more;
    for (int i = 0; i < 4; ++i) more.added.push_back({id++, {0.3 + 0.05 * step + 0.01 * i, 0, 0}});
    exact.apply(more);
    paper.apply(more);
    apply_to(cloud, more);
    const Truth t = brute_force(cloud, params.k, params.s_limit);
    std::size_t missed = 0;
    for (const auto& [pid, s] : t.s) missed += !(paper.s(pid) == s);
    missed_total += missed;
    expect_matches(exact, cloud);
  }
  MESSAGE("PaperAnnulus left " << missed_total << " affected points with a stale s over 5 steps");
  CHECK(missed_total > 0);
}

TEST_CASE("knn_tracker.tree_ties_match_brute_force_far_from_the_origin") {
  // A micro-cluster (1e-7 m) a million metres from the origin, seen from points spread over
  // 1e9 m: nanoflann's incremental box bound carries several ulps of rounding, so exact ties
  // (equal distances, decided by id) must still reach the collector.
  knnocc::test::Rng rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  std::size_t wrong = 0, queries = 0;
  for (int rep = 0; rep < 4; ++rep) {
    std::vector<Point3d> pts;
    std::vector<std::uint64_t> ids;
    const std::size_t n = 1500;
    for (std::size_t i = 0; i < n; ++i) {
      if (i % 30 == 0)
        pts.push_back({1e9 * (u(rng) - 0.5), 1e9 * (u(rng) - 0.5), 1e9 * (u(rng) - 0.5)});
      else
        pts.push_back({-1e6 + 1e-7 * u(rng), 5e5 + 1e-7 * u(rng), -3e6 + 1e-7 * u(rng)});
      ids.push_back(rng() % 100000000);
    }
    knnocc::PointIndex index(64);
    for (std::size_t i = 0; i < n; ++i) {
      index.append(ids[i], pts[i]);
      if (i % 97 == 0) index.flush();
    }
    index.flush();
    std::vector<knnocc::Neighbor> got, all;
    for (const std::size_t k : {1u, 3u, 10u})
      for (std::uint32_t q = 0; q < n; ++q) {
        index.knn(q, k, got);
        all.clear();
        for (std::uint32_t j = 0; j < n; ++j)
          if (j != q) all.push_back({j, ids[j], knnocc::dist2(pts[q], pts[j])});
        std::partial_sort(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(k), all.end(),
                          [](const knnocc::Neighbor& a, const knnocc::Neighbor& b) {
                            return knnocc::closer(a.d2, a.id, b.d2, b.id);
                          });
        bool same = got.size() == k;
        for (std::size_t j = 0; same && j < k; ++j) same = got[j].index == all[j].index;
        wrong += !same;
        ++queries;
      }
  }
  MESSAGE(queries << " k-NN queries compared with brute force");
  CHECK(wrong == 0);
}

TEST_CASE("knn_orbslam.incremental_equals_brute_force") {
  const std::string dir = knnocc::test::data_path("orbslam2_stereo_keyframes");
  if (dir.empty()) {
    knnocc::test::skip("skipped: ../shared/data/orbslam2_stereo_keyframes not available");
    return;
  }
  const auto seq = knnocc::io::Sequence::open(dir);
  REQUIRE(seq.size() == 249);
  knnocc::TrackerParams params;
  params.k = 8;
  params.rebuild_min = 256;  // the static-tree rebuild path runs many times on the way
  knnocc::KnnTracker<> tracker(params);
  knnocc::test::Cloud cloud;  // the map cloud so far
  knnocc::KeyframeUnion map_cloud;
  std::vector<knnocc::Point3d> world;
  std::vector<std::uint64_t> ids;
  for (std::size_t i = 0; i < seq.size(); ++i) {
    const auto kf = seq.load_cloud(i);
    REQUIRE(kf.ids.size() == kf.points.size());
    knnocc::io::keyframe_to_world(seq.pose(i), kf, 4.0, world, ids);
    const knnocc::ChangeSet cs = map_cloud.add(world, ids);
    tracker.apply(cs);
    for (const auto& a : cs.added) cloud[a.id] = a.p;
    CAPTURE(i);
    knnocc::test::expect_matches(tracker, cloud);  // k-NN sets, s, N, mu, sigma
  }
  MESSAGE(cloud.size() << " map points within 4 m after 249 keyframes; N " << tracker.N() << " mu "
                       << tracker.mu() << " sigma " << tracker.sigma());
}
