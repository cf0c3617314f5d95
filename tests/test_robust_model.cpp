// sensor/robust_model.hpp: each rule of the rating, and Mapper<RobustModel> end to end (views
// counted per map point, deferred evidence re-rated at confirmation, rejected points' evidence
// taken back, dense input without ids rated as OctoMap's model rates it).

#include <doctest/doctest.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <random>
#include <vector>

#include <knnocc/core/log_odds.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/sensor/knn_model.hpp>
#include <knnocc/sensor/robust_model.hpp>

using namespace knnocc;

namespace {
RunningNormal distribution(std::initializer_list<double> values) {
  RunningNormal d;
  for (double v : values) d.add(v);
  return d;
}
}  // namespace

TEST_CASE("robust model: the rating rules") {
  const RunningNormal dist = distribution({0.1, 0.2, 0.3, 0.2, 0.15});
  RobustModelParams p;
  const RobustModel m(p);
  const KnnModel knn(p.knn);
  PointContext c;
  c.s = 0.05;  // reliable
  SUBCASE("no map-point ids: OctoMap's hit and a ray") {
    c.views = 0;
    const EndpointRating r = m.rate(c, dist);
    CHECK(r.logodds == static_cast<float>(logodds(0.7)));
    CHECK(r.casts_ray);
  }
  SUBCASE("fewer views than min_views: nothing yet, no ray") {
    c.views = 2;
    const EndpointRating r = m.rate(c, dist);
    CHECK(r.logodds == 0.0f);
    CHECK_FALSE(r.casts_ray);
  }
  SUBCASE("the confirming keyframe adds the deferred evidence; later ones their own") {
    const double l = logodds(knn.probability(0.05, dist));
    c.views = 3;
    CHECK(m.rate(c, dist).logodds == doctest::Approx(3 * l));
    c.views = 4;
    c.committed = true;  // the map point added evidence before
    CHECK(m.rate(c, dist).logodds == doctest::Approx(l));
  }
  SUBCASE("a committed endpoint casts its ray from ray_views views on") {
    c.views = 3;
    CHECK(m.rate(c, dist).logodds > 0.0f);
    CHECK_FALSE(m.rate(c, dist).casts_ray);
    c.views = 4;
    c.committed = true;
    CHECK(m.rate(c, dist).casts_ray);
    RobustModelParams q;
    q.ray_views = 0;  // from min_views on
    c.views = 3;
    CHECK(RobustModel(q).rate(c, dist).casts_ray);
  }
  SUBCASE("a confirmed point is never pushed towards free (floor at P_w)") {
    c.views = 5;
    c.committed = true;
    c.s = 10.0;
    CHECK(knn.rate(10.0, dist).logodds < 0.0f);
    CHECK(m.rate(c, dist).logodds == doctest::Approx(logodds(p.knn.p_w)));
    c.s = std::numeric_limits<double>::quiet_NaN();
    CHECK(m.rate(c, dist).logodds == doctest::Approx(logodds(p.knn.p_w)));
  }
  SUBCASE("one keyframe's endpoints in a voxel add their mean") {
    c.views = 5;
    c.committed = true;
    c.in_voxel = 4;
    CHECK(m.rate(c, dist).logodds == doctest::Approx(logodds(knn.probability(0.05, dist)) / 4));
  }
  SUBCASE("a rejected point adds nothing and casts no ray") {
    RobustModelParams q;
    q.contra_min = 2;
    const RobustModel m2(q);
    CHECK_FALSE(m.rejects(4, 4));  // off by default
    CHECK(m.contradiction_radius() == 0.0);
    CHECK(m2.contradiction_radius() == doctest::Approx(0.05));
    c.views = 4;
    c.contradictions = 2;  // >= contra_min 2 and >= 0.5 * 4
    CHECK(m2.rejects(4, 2));
    CHECK(m2.rate(c, dist).logodds == 0.0f);
    CHECK_FALSE(m2.rate(c, dist).casts_ray);
    CHECK(m.rate(c, dist).logodds > 0.0f);
    CHECK_FALSE(m2.rejects(6, 2));  // 2 < 0.5 * 6
    CHECK_FALSE(m2.rejects(1, 1));  // < contra_min
  }
  SUBCASE("free_veto: a voxel with free evidence takes no occupied evidence") {
    RobustModelParams q;
    q.free_veto = -0.5;
    const RobustModel v(q);
    c.views = 4;
    c.voxel_logodds = -0.8f;
    CHECK(v.rate(c, dist).logodds == 0.0f);
    c.voxel_logodds = -0.2f;
    CHECK(v.rate(c, dist).logodds > 0.0f);
  }
  SUBCASE("a confirmed point without independent support waits; with it, it commits") {
    const double l = logodds(knn.probability(0.05, dist));
    c.views = 4;
    c.support = 0;
    CHECK(m.rate(c, dist).logodds == 0.0f);
    CHECK_FALSE(m.rate(c, dist).casts_ray);
    c.support = 1;  // first commitment: the deferred views at once
    CHECK(m.rate(c, dist).logodds == doctest::Approx(4 * l));
    c.committed = true;
    CHECK(m.rate(c, dist).logodds == doctest::Approx(l));
    CHECK(m.support_radius(4, dist) == doctest::Approx(1.75 * dist.mean()));
    CHECK(m.support_radius(1, dist) == 0.0);  // seen once: not counted
    RobustModelParams q;
    q.support_scale = 0;
    CHECK(RobustModel(q).support_radius(4, dist) == 0.0);
    // early commitment: two views and early_support (12) independent points
    c.committed = false;
    c.views = 2;
    c.support = 11;
    CHECK(m.rate(c, dist).logodds == 0.0f);
    c.support = 12;
    CHECK(m.rate(c, dist).logodds == doctest::Approx(2 * l));
    CHECK_FALSE(m.rate(c, dist).casts_ray);                 // rays from ray_views (4) on
    c.support = std::numeric_limits<std::uint32_t>::max();  // not counted: no early commitment
    CHECK(m.rate(c, dist).logodds == 0.0f);
    CHECK(m.support_radius(2, dist) > 0.0);
    CHECK(m.support_radius(1, dist) == 0.0);
  }
  SUBCASE("temporal consistency: a patch commits once seen min_span keyframes after its creator") {
    const double l = logodds(knn.probability(0.05, dist));
    c.views = 3;
    c.support = 1;
    c.siblings = 4;  // span_siblings (4) points of its own creator around it: a patch
    c.span = 4;      // all views within five consecutive keyframes
    CHECK(m.rate(c, dist).logodds == 0.0f);
    CHECK_FALSE(m.rate(c, dist).casts_ray);
    c.siblings = 3;  // not a patch
    CHECK(m.rate(c, dist).logodds == doctest::Approx(3 * l));
    c.siblings = 4;
    c.span = 5;  // min_span (5)
    CHECK(m.rate(c, dist).logodds == doctest::Approx(3 * l));
    c.span = 2;
    c.support = 8;  // surrounded: waits all the same (span_support off by default) ...
    CHECK(m.rate(c, dist).logodds == 0.0f);
    RobustModelParams q;
    q.span_support = 8;  // ... unless span_support points exempt it
    CHECK(RobustModel(q).rate(c, dist).logodds == doctest::Approx(3 * l));
    c.support = 1;
    q = {};
    q.min_span = 0;  // off
    CHECK(RobustModel(q).rate(c, dist).logodds == doctest::Approx(3 * l));
    q = {};
    q.span_siblings = 0;  // every point, patch or not
    c.siblings = 0;
    CHECK(RobustModel(q).rate(c, dist).logodds == 0.0f);
    CHECK(m.rate(c, dist).logodds == doctest::Approx(3 * l));
    c.committed = true;  // once committed on its own, the span no longer matters (support
    c.anchor = true;     // not counted)
    c.support = std::numeric_limits<std::uint32_t>::max();
    c.siblings = std::numeric_limits<std::uint32_t>::max();
    CHECK(RobustModel(q).rate(c, dist).logodds == doctest::Approx(l));
  }
  SUBCASE("lone_span: a point seen over that many keyframes needs no independent support") {
    const double l = logodds(knn.probability(0.05, dist));
    c.views = 3;
    c.support = 0;
    c.siblings = 0;
    c.span = 4;
    CHECK(m.rate(c, dist).logodds == 0.0f);
    c.span = 5;  // lone_span (5)
    CHECK(m.rate(c, dist).logodds == doctest::Approx(3 * l));
    RobustModelParams q;
    q.lone_span = 0;  // off
    CHECK(RobustModel(q).rate(c, dist).logodds == 0.0f);
  }
  SUBCASE("beside an anchor: a point held back adds its evidence, without a ray") {
    const double l = logodds(knn.probability(0.05, dist));
    c.views = 1;
    CHECK(m.wants_anchors(c));
    CHECK(m.rate(c, dist).logodds == 0.0f);  // anchors not counted
    c.anchors = 0;
    CHECK(m.rate(c, dist).logodds == 0.0f);
    c.anchors = 2;
    CHECK(m.rate(c, dist).logodds == doctest::Approx(l));
    CHECK_FALSE(m.rate(c, dist).casts_ray);
    c.views = 2;  // the deferred view too, as at confirmation
    CHECK(m.rate(c, dist).logodds == doctest::Approx(2 * l));
    CHECK(m.beside_evidence(c, dist) == doctest::Approx(2 * l));
    c.committed = true;  // added evidence before (beside an anchor): its own only
    CHECK(m.rate(c, dist).logodds == doctest::Approx(l));
    c.committed = false;
    c.views = 3;  // commits on its own: the anchors are not asked for
    c.support = 1;
    CHECK_FALSE(m.wants_anchors(c));
    RobustModelParams q;
    q.near_views = 0;  // off
    c.views = 2;
    CHECK_FALSE(RobustModel(q).wants_anchors(c));
    CHECK(RobustModel(q).rate(c, dist).logodds == 0.0f);
    CHECK(RobustModel(q).beside_evidence(c, dist) == 0.0f);
    q.near_views = 3;  // too few views
    CHECK(RobustModel(q).rate(c, dist).logodds == 0.0f);
    q = {};
    q.contra_min = 1;  // rejected by free-space evidence
    c.contradictions = 5;
    CHECK_FALSE(RobustModel(q).wants_anchors(c));
    CHECK(RobustModel(q).rate(c, dist).logodds == 0.0f);
  }
  SUBCASE("invalid parameters are refused") {
    RobustModelParams q;
    q.min_views = 0;
    CHECK_THROWS_AS(RobustModel{q}, std::invalid_argument);
    q = {};
    q.p_floor = 0.3;
    CHECK_THROWS_AS(RobustModel{q}, std::invalid_argument);
    q = {};
    q.free_veto = 1.0;
    CHECK_THROWS_AS(RobustModel{q}, std::invalid_argument);
  }
}

TEST_CASE("robust model in a Mapper: deferral, confirmation, views per map point") {
  Mapper<RobustModel> m(0.1);
  const Point3d origin{0, 0, 0};
  const std::vector<Point3d> pts{{2.05, 0.05, 0.05}};
  const std::vector<std::uint64_t> ids{42};
  OcKey k;
  REQUIRE(m.map().grid().point_to_key(pts[0], k));
  OcKey crossed;
  REQUIRE(m.map().grid().coord_to_key(1.05, 0.05, 0.05, crossed));
  m.insert_keyframe(origin, pts, ids);
  m.insert_keyframe(origin, pts, ids);
  CHECK_FALSE(m.map().logodds(k).has_value());        // deferred: its voxel untouched
  CHECK_FALSE(m.map().logodds(crossed).has_value());  // no ray yet
  CHECK(m.model().map_points().find(42)->views == 2);
  KeyframeStats ks = m.insert_keyframe(origin, pts, ids);
  CHECK(ks.rays == 0);  // rays from ray_views (4) views on
  // One point: no s (fewer than k neighbours), rated at the floor P_w, three times at once.
  REQUIRE(m.map().logodds(k).has_value());
  CHECK(*m.map().logodds(k) == doctest::Approx(3 * logodds(0.65)).epsilon(1e-5));
  CHECK_FALSE(m.map().logodds(crossed).has_value());
  CHECK(m.model().map_points().find(42)->views == 3);
  CHECK(m.model().map_points().find(42)->added == doctest::Approx(3 * logodds(0.65)).epsilon(1e-5));
  ks = m.insert_keyframe(origin, pts, ids);
  CHECK(ks.rays == 1);
  CHECK(*m.map().logodds(crossed) == doctest::Approx(logodds(0.4)));
  CHECK(*m.map().logodds(k) == doctest::Approx(4 * logodds(0.65)).epsilon(1e-5));
}

TEST_CASE("robust model in a Mapper: the keyframe span since a point's creator") {
  RobustModelParams params;
  params.span_support = std::numeric_limits<std::uint32_t>::max();  // never exempt
  params.span_siblings = 0;  // every point, not only patches (one point here)
  Mapper<RobustModel> m(0.1, RobustModel(params));
  const Point3d origin{0, 0, 0};
  const std::vector<Point3d> pts{{2.05, 0.05, 0.05}}, other{{0.05, 2.05, 0.05}};
  const std::vector<std::uint64_t> ids{42}, other_ids{7};
  OcKey k;
  REQUIRE(m.map().grid().point_to_key(pts[0], k));
  for (int kf = 0; kf < 3; ++kf) m.insert_keyframe(origin, pts, ids);  // keyframes 0, 1, 2
  m.insert_keyframe(origin, other, other_ids);                         // 3
  m.insert_keyframe(origin, pts, ids);                                 // 4: span 4
  CHECK(m.model().map_points().find(42)->views == 4);
  CHECK_FALSE(m.map().logodds(k).has_value());  // confirmed, but only 4 keyframes after its creator
  m.insert_keyframe(origin, pts, ids);          // 5: span 5, all five views at once (floor P_w)
  REQUIRE(m.map().logodds(k).has_value());
  CHECK(*m.map().logodds(k) == doctest::Approx(5 * logodds(0.65)).epsilon(1e-5));
}

TEST_CASE("robust model in a Mapper: rays of other keyframes through a point take it back") {
  RobustModelParams params;
  params.contra_min = 2;  // off by default
  Mapper<RobustModel> m(0.1, RobustModel(params));
  const std::vector<Point3d> pt{{2.05, 0.05, 0.05}};
  for (int i = 0; i < 3; ++i) m.insert_keyframe(Point3d{0, 0, 0}, pt, {7});
  OcKey k;
  REQUIRE(m.map().grid().point_to_key(pt[0], k));
  REQUIRE(m.map().is_occupied(*m.map().logodds(k)));
  // Another point seen from elsewhere: confirmed first (3 keyframes), then its rays pass
  // through point 7 and end 2 m behind it.
  const Point3d side{2.05, -3.0, 0.05};
  const std::vector<Point3d> behind{{2.05, 2.0, 0.05}};
  // (no ray before point 8 has ray_views (4) views: the 4th and 5th keyframes contradict 7)
  for (int i = 0; i < 5; ++i) m.insert_keyframe(side, behind, {8});
  const auto* p = m.model().map_points().find(7);
  REQUIRE(p != nullptr);
  CHECK(p->contra >= 2);
  CHECK(p->rejected);
  CHECK_FALSE(m.map().is_occupied(*m.map().logodds(k)));
  // Observing it again adds nothing.
  m.insert_keyframe(Point3d{0, 0, 0}, pt, {7});
  CHECK_FALSE(m.map().is_occupied(*m.map().logodds(k)));
}

TEST_CASE("robust model in a Mapper: independent support against a brute-force count") {
  // Random keyframes observing map points of a few small clusters, each cluster created by one
  // keyframe, plus scattered points; contradictions off. A point commits on its own (becomes an
  // anchor) at the first keyframe where it is confirmed and another keyframe's point lies within
  // 1.75 mu (or, when it is not a patch, lone_span keyframes passed since its creator), unless
  // it is a patch (span_siblings points of its creator within 1.75 mu) seen within min_span
  // keyframes of its creator and not surrounded. With the near rule, a point seen by near_views
  // keyframes commits beside an anchor: observed with an anchor of an earlier keyframe in the 27
  // voxels around it, or at the end of the keyframe that made one there.
  RobustModelParams params;
  params.knn.k = 3;
  params.early_support = 2;  // (12 by default) so that two-view points commit here too
  params.span_siblings = 3;  // (4 by default) a cluster's points are patches here
  params.span_support = 5;
  params.contra_min = 0;
  SUBCASE("lone rule for points that are not patches, near rule (the defaults)") {}
  SUBCASE("lone rule for patches too") { params.lone_patches = true; }
  SUBCASE("near rule off") { params.near_views = 0; }
  SUBCASE("near rule from two views") { params.near_views = 2; }
  Mapper<RobustModel> m(0.1, RobustModel(params));
  const Grid<OcKey>& grid = m.map().grid();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-2.0, 2.0), g(-0.04, 0.04);
  std::uniform_int_distribution<int> coin(0, 3);
  std::vector<Point3d> pos;
  std::vector<OcKey> key;  // the voxel of each point (the ledger's, from its double position)
  std::vector<std::size_t> creator;
  std::vector<bool> committed, anchor;
  std::size_t commits = 0, waits = 0, early = 0, span_waits = 0, lone = 0, near_seen = 0,
              near_later = 0;
  auto anchor_beside = [&](const OcKey& k, const std::vector<bool>& anchors) {
    for (std::size_t o = 0; o < pos.size(); ++o)
      if (anchors[o] && std::abs(int(key[o][0]) - int(k[0])) <= 1 &&
          std::abs(int(key[o][1]) - int(k[1])) <= 1 && std::abs(int(key[o][2]) - int(k[2])) <= 1)
        return true;
    return false;
  };
  for (std::size_t kf = 0; kf < 30; ++kf) {
    std::vector<Point3d> pts;
    std::vector<std::uint64_t> ids;
    // re-observe some earlier points
    for (std::size_t i = 0; i < pos.size(); ++i)
      if (coin(rng) == 0) {
        pts.push_back(pos[i]);
        ids.push_back(i);
      }
    // a new cluster of 4 points and 3 scattered points, created by this keyframe
    const Point3d c{u(rng), u(rng), u(rng) * 0.2 + 3.0};
    for (int j = 0; j < 7; ++j) {
      const Point3d p = j < 4 ? Point3d{c.x + g(rng), c.y + g(rng), c.z + g(rng)}
                              : Point3d{u(rng), u(rng), u(rng) * 0.2 + 3.0};
      pts.push_back(p);
      ids.push_back(pos.size());
      pos.push_back(p);
      OcKey k;
      REQUIRE(grid.point_to_key(p, k));
      key.push_back(k);
      creator.push_back(kf);
      committed.push_back(false);
      anchor.push_back(false);
    }
    m.insert_keyframe(Point3d{0, 0, 0}, pts, ids);
    const double r = params.support_scale * m.tracker().mu();
    const std::vector<bool> anchors_before = anchor;
    std::vector<bool> expect = committed;
    for (const std::uint64_t id : ids) {
      const auto* e = m.model().map_points().find(id);
      REQUIRE(e != nullptr);
      if (anchor[id]) continue;
      std::uint32_t support = 0, siblings = 0;
      for (std::size_t o = 0; o < pos.size(); ++o) {
        const double dx = pos[o].x - pos[id].x, dy = pos[o].y - pos[id].y,
                     dz = pos[o].z - pos[id].z;
        if (o == id || dx * dx + dy * dy + dz * dz > r * r) continue;
        ++(creator[o] != creator[id] ? support : siblings);
      }
      const std::size_t span = kf - creator[id];
      const bool patch = siblings >= params.span_siblings;
      const bool supported =
          support >= 1 || (span >= params.lone_span && (params.lone_patches || !patch));
      const bool waits_span = span < params.min_span && support < params.span_support && patch;
      const bool confirmed = (e->views >= params.min_views && supported) ||
                             (e->views >= params.early_views && support >= params.early_support);
      OcKey k;  // the endpoint's voxel, as the scan sees it (float)
      REQUIRE(grid.point_to_key(detail::to_point3f(pos[id]), k));
      if (confirmed && !waits_span) {
        anchor[id] = expect[id] = true;
        early += e->views < params.min_views;
        lone += support == 0;
      } else if (params.near_views > 0 && e->views >= params.near_views &&
                 anchor_beside(k, anchors_before)) {
        near_seen += !expect[id];
        expect[id] = true;
      }
      span_waits += confirmed && waits_span;
      waits += e->views >= params.min_views && !supported;
    }
    // points held back beside this keyframe's new anchors commit at its end
    if (params.near_views > 0)
      for (std::size_t o = 0; o < pos.size(); ++o)
        if (!expect[o] && m.model().map_points().find(o)->views >= params.near_views &&
            anchor_beside(key[o], anchor)) {
          expect[o] = true;
          ++near_later;
        }
    for (std::size_t o = 0; o < pos.size(); ++o) {
      const auto* e = m.model().map_points().find(o);
      REQUIRE(e != nullptr);
      CHECK(e->anchor == anchor[o]);
      CHECK((e->added != 0.0f) == expect[o]);
      commits += expect[o] && !committed[o];
    }
    committed = expect;
  }
  CHECK(commits > 20);
  CHECK(waits > 5);
  CHECK(early > 0);
  CHECK(span_waits > 0);
  CHECK(lone > 0);
  if (params.near_views > 0) {
    CHECK(near_seen > 0);
    CHECK(near_later > 0);
  }
}

TEST_CASE("robust model without map-point ids maps as the OctoMap model") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-3.0f, 3.0f);
  Mapper<RobustModel> robust(0.1);
  Mapper<OctoMapModel> octo(0.1);
  for (int s = 0; s < 4; ++s) {
    std::vector<Point3f> pts;
    for (int i = 0; i < 500; ++i) pts.push_back({u(rng), u(rng), u(rng) * 0.3f});
    const Point3f o{u(rng) * 0.1f, u(rng) * 0.1f, 0.0f};
    robust.insert_keyframe(o, pts);
    octo.insert_keyframe(o, pts);
  }
  std::size_t n = 0, differ = 0;
  octo.map().for_each_voxel([&](const OcKey& k, float v) {
    ++n;
    const auto r = robust.map().logodds(k);
    if (!r || std::fabs(*r - v) > 1e-5f) {
      ++differ;
      if (differ < 5) MESSAGE("octomap " << v << " robust " << (r ? *r : -99.0f));
    }
  });
  CHECK(n > 1000);
  CHECK(differ == 0);
  CHECK(robust.map().count_voxels().occupied == octo.map().count_voxels().occupied);
  CHECK(robust.map().count_voxels().free == octo.map().count_voxels().free);
}

TEST_CASE("robust model without map-point ids keeps no map point cloud") {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  std::vector<Point3d> pts;
  for (int i = 0; i < 300; ++i) pts.push_back({u(rng), u(rng), u(rng) * 0.3});
  const std::vector<std::uint64_t> ids(pts.size(), 7);
  Mapper<RobustModel> robust(0.1);
  const KeyframeStats ks = robust.insert_keyframe(Point3d{0, 0, 0}, pts);
  CHECK(ks.rated == pts.size());
  CHECK(ks.rays == pts.size());
  CHECK(ks.tracker.added == 0);
  CHECK(robust.tracker().size() == 0);  // the model rates them without it
  CHECK(robust.model().map_points().size() == 0);
  CHECK(robust.map().count_voxels().occupied > 100);
  // a sequence either always or never gives ids, both ways round
  CHECK_THROWS_AS(robust.insert_keyframe(Point3d{0, 0, 0}, pts, ids), std::invalid_argument);
  Mapper<RobustModel> with_ids(0.1);
  with_ids.insert_keyframe(Point3d{0, 0, 0}, pts, ids);
  CHECK(with_ids.tracker().size() == 1);
  CHECK_THROWS_AS(with_ids.insert_keyframe(Point3d{0, 0, 0}, pts), std::invalid_argument);
  // the k-NN model keeps the cloud of keyframes without ids (its s needs it)
  Mapper<KnnModel> knn(0.1);
  knn.insert_keyframe(Point3d{0, 0, 0}, pts);
  CHECK(knn.tracker().size() == pts.size());
}
