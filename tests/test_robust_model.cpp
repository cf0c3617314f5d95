// sensor/robust_model.hpp and sensor/real_point_mixture.hpp: the mixture recovers the rates of a
// synthetic two-class sample, and its EM step equals its formulas summed point by point; the
// model's ledger (views, creator, latest detection, independent support) and see-through counts
// (each map point a ray ends at counting once per voxel) equal a brute-force recomputation from the
// keyframes; every map point is believed exactly when its posterior says so, and a voxel whose
// points are all disbelieved is not occupied; rays from a point's third detection, none through a
// voxel holding another believed point; SLAM evidence reaches the model; dense input without ids is
// mapped as the OctoMap model maps it.

#include <doctest/doctest.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <vector>

#include <knnocc/core/log_odds.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/raycast/dda.hpp>
#include <knnocc/sensor/knn_model.hpp>
#include <knnocc/sensor/real_point_mixture.hpp>
#include <knnocc/sensor/robust_model.hpp>

using namespace knnocc;

namespace {

// A two-class sample: real points rarely seen through and well supported, wrong ones often seen
// through and alone; found/visible counts when `slam`.
struct Sample {
  std::vector<PointCounts> counts;
  std::vector<bool> real;
};
Sample make_sample(std::uint32_t seed, std::size_t n, bool slam, double e_wrong = 0.45) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  auto geometric = [&](double mean) {
    std::geometric_distribution<std::uint32_t> g(1.0 / (1.0 + mean));
    return g(rng);
  };
  Sample s;
  for (std::size_t i = 0; i < n; ++i) {
    const bool real = u01(rng) < 0.8;
    PointCounts k;
    const std::uint32_t met = 1 + geometric(6.0);
    std::binomial_distribution<std::uint32_t> pass(met, real ? 0.03 : e_wrong);
    k.c = pass(rng);
    k.d = met - k.c;
    if (k.d == 0) k.d = 1;  // a map point is detected at least once
    k.u = geometric(real ? 25.0 : 1.5);
    if (slam) {
      k.v = 1 + geometric(8.0);
      std::binomial_distribution<std::uint32_t> found(k.v, real ? 0.7 : 0.1);
      k.f = found(rng);
    }
    k.g = geometric(3.0);
    s.counts.push_back(k);
    s.real.push_back(real);
  }
  return s;
}

double accuracy(const RealPointMixture& m, const Sample& s) {
  std::size_t right = 0;
  for (std::size_t i = 0; i < s.counts.size(); ++i)
    right += (m.log_odds(s.counts[i]) >= 0) == s.real[i];
  return double(right) / double(s.counts.size());
}

RealPointMixture fitted(const Sample& s, MixtureTerms terms = {}) {
  RealPointMixture m(terms);
  for (const PointCounts& k : s.counts) m.add(k);
  m.fit();
  return m;
}

}  // namespace

TEST_CASE("robust mixture: recovers the rates of a two-class sample and classifies it") {
  const Sample s = make_sample(3, 20000, false);
  const RealPointMixture m = fitted(s);
  const RealPointRates& r = m.rates();
  CHECK(r.prior == doctest::Approx(0.8).epsilon(0.03));
  CHECK(r.e_real == doctest::Approx(0.03).epsilon(0.15));
  CHECK(r.e_wrong == doctest::Approx(0.45).epsilon(0.05));
  CHECK(r.u_real == doctest::Approx(25.0).epsilon(0.05));
  CHECK(r.u_wrong == doctest::Approx(1.5).epsilon(0.1));
  CHECK(accuracy(m, s) > 0.94);
  CHECK(m.bins() < s.counts.size());  // equal counts share a bin
  // With geometric support each step is an EM step: from the starting rates every step raises
  // the likelihood of this large sample (the pseudo-observations weigh nothing next to 20,000
  // points). The negative binomial variant's variance is a moment step, so its fit is only
  // checked to end far above where it started.
  RealPointMixture step(MixtureTerms{});
  for (const PointCounts& k : s.counts) step.add(k);
  double before = step.log_likelihood();
  for (int i = 0; i < 30; ++i) {
    step.step();
    const double now = step.log_likelihood();
    CHECK(now >= before - 1e-9 * std::fabs(before));
    before = now;
  }
  RealPointMixture nb(MixtureTerms{false, true}), start(MixtureTerms{false, true});
  for (const PointCounts& k : s.counts) nb.add(k), start.add(k);
  nb.fit();
  CHECK(nb.log_likelihood() > start.log_likelihood() + 1000.0);
}

TEST_CASE("robust mixture: each EM step is the update its formulas give, point by point") {
  // Points far on the real side (P(real) exactly 1, which step() sums without exp) and all others.
  const Sample s = make_sample(9, 3000, true);
  RealPointMixture m;
  for (const PointCounts& k : s.counts) m.add(k);
  for (int i = 0; i < 8; ++i) m.step();
  for (int round = 0; round < 5; ++round) {
    const RealPointRates before = m.rates();
    double n = 0, w = 0, w_n = 0, w_c = 0, v_n = 0, v_c = 0, w_u = 0, v_u = 0, w_f = 0, w_v = 0,
           v_f = 0, v_v = 0, w_uu = 0, v_uu = 0;
    std::size_t certain = 0;
    for (const PointCounts& k : s.counts) {
      const double l = m.log_odds(k), p = 1.0 / (1.0 + std::exp(-l)), q = 1.0 - p;
      certain += l >= 37.0;
      const double met = double(k.d) + k.c;
      n += 1, w += p, w_n += p * met, w_c += p * k.c, v_n += q * met, v_c += q * k.c;
      w_u += p * k.u, v_u += q * k.u, w_f += p * k.f, w_v += p * k.v, v_f += q * k.f,
          v_v += q * k.v, w_uu += p * k.u * k.u, v_uu += q * k.u * k.u;
    }
    CHECK(certain > 100);
    CHECK(certain < s.counts.size() - 100);
    m.step();
    const RealPointRates& r = m.rates();
    REQUIRE(before.e_real < before.e_wrong);
    CHECK(r.prior == doctest::Approx((w + 1) / (n + 2)).epsilon(1e-12));
    CHECK(r.e_real == doctest::Approx((w_c + 1) / (w_n + 2)).epsilon(1e-12));
    CHECK(r.e_wrong == doctest::Approx((v_c + 1) / (v_n + 2)).epsilon(1e-12));
    CHECK(r.u_real == doctest::Approx((w_u + 1) / (w + 1)).epsilon(1e-12));
    CHECK(r.u_wrong == doctest::Approx((v_u + 1) / (n - w + 1)).epsilon(1e-12));
    CHECK(r.f_real == doctest::Approx((w_f + 1) / (w_v + 2)).epsilon(1e-12));
    CHECK(r.f_wrong == doctest::Approx((v_f + 1) / (v_v + 2)).epsilon(1e-12));
    const double mr = (w_u + 1) / (w + 1), mw = (v_u + 1) / (n - w + 1);
    CHECK(r.u_var_real == doctest::Approx((w_uu + 1) / (w + 1) - mr * mr).epsilon(1e-9));
    CHECK(r.u_var_wrong == doctest::Approx((v_uu + 1) / (n - w + 1) - mw * mw).epsilon(1e-9));
  }
}

TEST_CASE("robust mixture: the SLAM system's found/visible counts count when given") {
  // See-throughs and support hardly differ here; found/visible does.
  Sample s = make_sample(5, 20000, true, 0.06);
  for (std::size_t i = 0; i < s.counts.size(); ++i) s.counts[i].u = s.real[i] ? 3 : 2;
  const RealPointMixture with = fitted(s);
  CHECK(with.rates().f_real == doctest::Approx(0.7).epsilon(0.05));
  CHECK(with.rates().f_wrong == doctest::Approx(0.1).epsilon(0.2));
  Sample without = s;
  for (PointCounts& k : without.counts) k.f = k.v = 0;
  const RealPointMixture plain = fitted(without);
  CHECK(accuracy(with, s) > 0.93);
  CHECK(accuracy(with, s) > accuracy(plain, without) + 0.1);
}

TEST_CASE("robust mixture, negative binomial variant: little support is strong evidence") {
  // Real points' support near 50 (as on the simulator's surfaces), wrong ones' near 3, and a
  // wrong match re-detected often: detections say real, its support says wrong.
  std::mt19937 rng(13);
  std::poisson_distribution<std::uint32_t> real_u(50.0), wrong_u(3.0);
  RealPointMixture nb(MixtureTerms{false, true}), geometric;
  for (int i = 0; i < 20000; ++i) {
    const bool real = i % 5 != 0;
    PointCounts k{real ? 5u : 3u, real ? 0u : 2u, real ? real_u(rng) : wrong_u(rng), 0, 0, 0};
    nb.add(k);
    geometric.add(k);
  }
  nb.fit();
  geometric.fit();
  CHECK(nb.rates().u_var_real == doctest::Approx(50.0).epsilon(0.1));  // Poisson: variance = mean
  const PointCounts redetected{13, 1, 4, 0, 0, 0}, real_point{5, 0, 48, 0, 0, 0};
  CHECK(nb.log_odds(redetected) < geometric.log_odds(redetected) - 10);
  CHECK(nb.log_odds(redetected) < -10);
  CHECK(nb.log_odds(real_point) > 10);
  CHECK(std::isfinite(nb.log_odds(PointCounts{5, 0, 5000, 0, 0, 0})));  // past the cache
}

TEST_CASE("robust mixture: the gap term only when turned on") {
  const Sample s = make_sample(7, 2000, false);
  const RealPointMixture off = fitted(s), on = fitted(s, MixtureTerms{true});
  PointCounts a{5, 0, 10, 0, 0, 0}, b = a;
  b.g = 30;
  CHECK(off.log_odds(a) == off.log_odds(b));
  CHECK(on.log_odds(a) != on.log_odds(b));
}

namespace {

struct Keyframe {
  Point3d origin;
  std::vector<Point3d> points;
  std::vector<std::uint64_t> ids;
};

// A sparse surface (a vertical wall of map points at x = 3) seen by keyframes moving along it,
// each detecting a random half of the points in front of it; wrong matches floating between the
// camera and the wall, in patches of three, re-observed by the next keyframe now and then.
std::vector<Keyframe> wall_sequence(std::uint32_t seed, std::size_t frames) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Point3d> wall;
  for (int i = 0; i < 600; ++i) wall.push_back({3.0 + 0.05 * u(rng), 6.0 * u(rng), 2.0 * u(rng)});
  std::vector<Keyframe> kfs;
  std::uint64_t next_wrong = 100000;
  std::vector<std::pair<std::uint64_t, Point3d>> last_patch;
  for (std::size_t f = 0; f < frames; ++f) {
    Keyframe kf;
    kf.origin = {0.0, 0.5 + 5.0 * double(f) / double(frames), 1.0};
    for (std::size_t i = 0; i < wall.size(); ++i)
      if (std::fabs(wall[i].y - kf.origin.y) < 1.5 && u(rng) < 0.5) {
        kf.points.push_back(wall[i]);
        kf.ids.push_back(i);
      }
    if (!last_patch.empty() && u(rng) < 0.5)
      for (const auto& [id, p] : last_patch) {
        kf.points.push_back(p);
        kf.ids.push_back(id);
      }
    last_patch.clear();
    const Point3d c{0.8 + 1.6 * u(rng), kf.origin.y + u(rng) - 0.5, 0.3 + 1.4 * u(rng)};
    for (int j = 0; j < 3; ++j) {
      const Point3d p{c.x + 0.02 * j, c.y, c.z + 0.02 * j};
      kf.points.push_back(p);
      kf.ids.push_back(next_wrong);
      last_patch.push_back({next_wrong++, p});
    }
    kfs.push_back(std::move(kf));
  }
  return kfs;
}

}  // namespace

TEST_CASE("robust model: its ledger and see-throughs equal a brute-force recomputation") {
  const auto kfs = wall_sequence(13, 40);
  Mapper<RobustModel> mapper(0.1);
  std::vector<double> radius;  // per keyframe: margin_scale * mu after its change (0: no scale)
  for (const Keyframe& kf : kfs) {
    mapper.insert_keyframe(kf.origin, kf.points, kf.ids);
    const RunningNormal& d = mapper.tracker().distribution();
    radius.push_back(d.count() > 0 ? mapper.model().params().margin_scale * d.mean() : 0.0);
  }
  const RobustModel& model = mapper.model();
  const Grid<OcKey>& grid = mapper.map().grid();

  // Detections, creators, latest detections, first positions.
  struct Truth {
    Point3d pos;
    std::uint32_t views = 0, first = 0, last = 0, support = 0;
  };
  std::map<std::uint64_t, Truth> truth;
  for (std::uint32_t t = 0; t < kfs.size(); ++t) {
    std::set<std::uint64_t> seen;
    for (std::size_t j = 0; j < kfs[t].ids.size(); ++j) {
      const std::uint64_t id = kfs[t].ids[j];
      if (!seen.insert(id).second) continue;
      auto [it, fresh] = truth.try_emplace(id);
      if (fresh) it->second.pos = kfs[t].points[j], it->second.first = t;
      ++it->second.views;
      it->second.last = t;
    }
  }
  // Independent support: a pair of points of different creators within the radius of the later
  // creator's keyframe.
  for (auto a = truth.begin(); a != truth.end(); ++a)
    for (auto b = std::next(a); b != truth.end(); ++b) {
      if (a->second.first == b->second.first) continue;
      const double r = radius[std::max(a->second.first, b->second.first)];
      const double dx = a->second.pos.x - b->second.pos.x, dy = a->second.pos.y - b->second.pos.y,
                   dz = a->second.pos.z - b->second.pos.z;
      if (r > 0 && dx * dx + dy * dy + dz * dz <= r * r) {
        ++a->second.support;
        ++b->second.support;
      }
    }
  // See-throughs per voxel: every keyframe's rays, shortened by its margin, walked voxel by voxel;
  // once a voxel holds a map point (from the keyframe that first detected one there), a keyframe
  // counts only when one of its rays through the voxel ends at a map point whose rays never
  // crossed it since.
  std::map<std::uint64_t, std::uint32_t> holds_from;  // voxel -> first keyframe with a point in it
  for (const auto& [id, t] : truth) {
    OcKey k;
    REQUIRE(grid.point_to_key(detail::to_point3f(t.pos), k));
    auto [it, fresh] = holds_from.try_emplace(k.pack(), t.first);
    if (!fresh) it->second = std::min(it->second, t.first);
  }
  std::map<std::uint64_t, std::uint32_t> passes;
  std::map<std::uint64_t, std::set<std::uint64_t>> witnesses;  // voxel -> ids whose rays crossed it
  std::vector<OcKey> ray;
  std::size_t repeated = 0;  // keyframes not counted because their witnesses were not new
  for (std::uint32_t t = 0; t < kfs.size(); ++t) {
    if (radius[t] == 0) continue;
    std::map<std::uint64_t, std::set<std::uint64_t>> crossed;  // voxel -> ids of the rays
    const Point3d& o = kfs[t].origin;
    for (std::size_t j = 0; j < kfs[t].points.size(); ++j) {
      const Point3d& p = kfs[t].points[j];
      const double len = std::sqrt((p.x - o.x) * (p.x - o.x) + (p.y - o.y) * (p.y - o.y) +
                                   (p.z - o.z) * (p.z - o.z));
      if (!(len > radius[t])) continue;
      const double f = (len - radius[t]) / len;
      const Point3d stop{o.x + (p.x - o.x) * f, o.y + (p.y - o.y) * f, o.z + (p.z - o.z) * f};
      REQUIRE(compute_ray_keys(grid, detail::to_point3f(o), detail::to_point3f(stop), ray));
      for (const OcKey& k : ray) crossed[k.pack()].insert(kfs[t].ids[j]);
    }
    for (const auto& [k, ids] : crossed) {
      const auto h = holds_from.find(k);
      bool fresh = h == holds_from.end() || h->second > t;
      if (!fresh)
        for (const std::uint64_t id : ids) fresh = witnesses[k].insert(id).second || fresh;
      if (fresh)
        ++passes[k];
      else
        ++repeated;
    }
  }
  CHECK(repeated > 20);  // witnesses are exercised

  REQUIRE(model.map_points().size() == truth.size());
  std::size_t seen_through = 0, disbelieved = 0, supported = 0;
  std::map<std::uint64_t, std::uint32_t> believed_in;  // voxel -> believed points
  std::set<std::uint64_t> voxels;
  for (const auto& entry : truth) {
    const std::uint64_t id = entry.first;  // not a structured binding: CAPTURE captures it
    const auto& t = entry.second;
    CAPTURE(id);
    const MapPointLedger::Point* p = model.map_points().find(id);
    REQUIRE(p != nullptr);
    CHECK(p->views == t.views);
    CHECK(p->first == t.first);
    CHECK(p->last == t.last);
    CHECK(p->support == t.support);
    OcKey k;
    REQUIRE(grid.point_to_key(detail::to_point3f(t.pos), k));
    REQUIRE(p->has_key);
    CHECK(p->key == k.pack());
    const auto it = passes.find(k.pack());
    const std::uint32_t c = it == passes.end() ? 0 : it->second;
    CHECK(model.counts(*p).c == c);
    CHECK(model.counts(*p).d == t.views);
    // Believed exactly when the posterior says so, with the rates of the last keyframe.
    CHECK(p->believed == (model.real_log_odds(*p) >= 0.0));
    seen_through += c > 0;
    supported += t.support > 0;
    disbelieved += !p->believed;
    believed_in[k.pack()] += p->believed;
    voxels.insert(k.pack());
  }
  CHECK(seen_through > 20);  // the brute force is exercised ...
  CHECK(supported > 100);
  CHECK(disbelieved > 5);  // ... and so is taking evidence back
  CHECK(model.wrong_class_found());
  for (const std::uint64_t v : voxels) {
    const std::uint32_t s = model.voxels().find(OcKey::unpack(v));
    REQUIRE(s != VoxelTally::kNone);
    CHECK(model.voxels().at(s).believed == believed_in[v]);
    // A voxel whose points are all disbelieved is not left occupied.
    if (believed_in[v] == 0) {
      const auto value = mapper.map().logodds(OcKey::unpack(v));
      if (value) CHECK_FALSE(mapper.map().is_occupied(*value));
    }
  }
  // The floating wrong patches are mostly not believed, the wall mostly is.
  std::size_t wrong = 0, wrong_believed = 0, wall = 0, wall_believed = 0;
  for (const auto& [id, t] : truth) {
    const bool believed = model.map_points().find(id)->believed;
    if (id >= 100000) {
      ++wrong;
      wrong_believed += believed;
    } else {
      ++wall;
      wall_believed += believed;
    }
  }
  CHECK(double(wall_believed) > 0.9 * double(wall));
  CHECK(double(wrong_believed) < 0.5 * double(wrong));
}

TEST_CASE("robust model: rays from a point's third detection, evidence of eq 13") {
  RobustModelParams params;
  params.knn.k = 50;  // no valid s (N = 0): eq 13 gives every endpoint P_w = 0.65
  Mapper<RobustModel> m(0.1, RobustModel(params));
  const Point3d origin{0.05, 0.05, 0.05};
  const std::vector<Point3d> pts{{2.05, 0.05, 0.05}};
  const std::vector<std::uint64_t> ids{42};
  OcKey k, crossed;
  REQUIRE(m.map().grid().point_to_key(pts[0], k));
  REQUIRE(m.map().grid().coord_to_key(1.05, 0.05, 0.05, crossed));
  KeyframeStats ks = m.insert_keyframe(origin, pts, ids);
  CHECK(ks.rays == 0);  // one detection: no ray
  CHECK_FALSE(m.map().logodds(crossed).has_value());
  REQUIRE(m.map().logodds(k).has_value());
  CHECK(*m.map().logodds(k) == doctest::Approx(logodds(0.65)).epsilon(1e-5));
  ks = m.insert_keyframe(origin, pts, ids);
  CHECK(ks.rays == 0);  // two detections: still none
  CHECK_FALSE(m.map().logodds(crossed).has_value());
  CHECK(*m.map().logodds(k) == doctest::Approx(2 * logodds(0.65)).epsilon(1e-5));
  ks = m.insert_keyframe(origin, pts, ids);
  CHECK(ks.rays == 1);
  CHECK(*m.map().logodds(crossed) == doctest::Approx(logodds(0.4)));  // the free update
  CHECK(*m.map().logodds(k) == doctest::Approx(3 * logodds(0.65)).epsilon(1e-5));
  CHECK(m.model().map_points().find(42)->views == 3);
}

namespace {
struct FloorSeenThrough : RobustRules {
  static constexpr bool floor_when_seen_through = true;
};
// A lone map point L (id 100) 1 m from a row of ten points 0.1 m apart (k = 1: s 1 against 0.1,
// so eq 13 rates L below P_w), detected by every keyframe; keyframe `behind` also detects a point
// 2 m straight behind L (id 200), whose ray sees through L's voxel. Returns L's voxel's log-odds
// after each keyframe.
template <class Model>
std::vector<float> lone_point(Mapper<Model>& m, std::size_t frames, std::size_t behind) {
  std::vector<float> out;
  for (std::size_t f = 0; f < frames; ++f) {
    std::vector<Point3d> pts;
    std::vector<std::uint64_t> ids;
    for (int i = 0; i < 10; ++i) {
      pts.push_back({2.05, 1.05 + 0.1 * i, 0.05});
      ids.push_back(static_cast<std::uint64_t>(i));
    }
    pts.push_back({2.05, 0.05, 0.05});
    ids.push_back(100);
    if (f == behind) {
      pts.push_back({4.05, 0.05, 0.05});
      ids.push_back(200);
    }
    m.insert_keyframe(Point3d{0.05, 0.05, 0.05}, pts, ids);
    OcKey k;
    REQUIRE(m.map().grid().point_to_key(pts[10], k));
    out.push_back(m.map().logodds(k).value_or(0.0f));
  }
  return out;
}
}  // namespace

TEST_CASE("robust model: the strength floor holds until a keyframe sees through the point") {
  RobustModelParams params;
  params.knn.k = 1;
  Mapper<RobustModel> model(0.1, RobustModel(params));
  Mapper<BasicRobustModel<FloorSeenThrough>> floored(0.1,
                                                     BasicRobustModel<FloorSeenThrough>(params));
  const std::vector<float> a = lone_point(model, 5, 2), b = lone_point(floored, 5, 2);
  const float floor = static_cast<float>(logodds(params.knn.p_w));
  // Up to the keyframe that sees through L, both rules add the same: from the second detection on,
  // P_w (eq 13 alone would add less).
  for (std::size_t f = 0; f <= 2; ++f) CHECK(a[f] == b[f]);
  CHECK(a[2] - a[1] == doctest::Approx(floor).epsilon(1e-5));
  const MapPointLedger::Point* lone = model.model().map_points().find(100);
  REQUIRE(lone != nullptr);
  CHECK(model.model().counts(*lone).c == 1);
  CHECK(lone->believed);
  // From the next detection on, eq 13 rates L as it is: below the floor, here below 1/2.
  for (std::size_t f = 3; f < 5; ++f) {
    CHECK(b[f] - b[f - 1] == doctest::Approx(floor).epsilon(1e-5));
    CHECK(a[f] - a[f - 1] < 0.0f);
  }
}

namespace {
// A keyframe ray through a believed point: a wall of map points at x = 1 and one map point, id
// 9999, at x = 2 straight behind the wall point in the voxel at (1.05, 0.05, 0.05), all detected by
// `frames` keyframes from the same origin; returns the rays cast by the last keyframe.
template <class Model>
std::size_t behind_the_wall(Mapper<Model>& m, std::size_t frames) {
  std::vector<Point3d> pts;
  std::vector<std::uint64_t> ids;
  for (int y = -5; y <= 5; ++y)
    for (int z = -5; z <= 5; ++z) {
      pts.push_back({1.05, 0.05 + 0.1 * y, 0.05 + 0.1 * z});
      ids.push_back(ids.size());
    }
  pts.push_back({2.05, 0.05, 0.05});
  ids.push_back(9999);
  KeyframeStats ks;
  const Point3d origin{0.05, 0.05, 0.05};
  for (std::size_t f = 0; f < frames; ++f) ks = m.insert_keyframe(origin, pts, ids);
  return ks.rays;
}
// The mixture used whether or not its wrong class is less supported (in this small scene it is
// not, so the library's model believes every point and casts every ray).
struct MixtureAlwaysUsed : RobustRules {
  static constexpr bool support_check = false;
};
struct RaysThroughBelieved : MixtureAlwaysUsed {
  static constexpr bool rays_through_believed = true;
};
struct SeeThroughPerKeyframe : MixtureAlwaysUsed {
  static constexpr bool witness_once = false;
};
template <class Rules = MixtureAlwaysUsed>
using DecidingModel = BasicRobustModel<Rules>;
}  // namespace

TEST_CASE("robust model: no free ray through a voxel holding another believed point") {
  Mapper<DecidingModel<>> m(0.1);
  const std::size_t rays = behind_the_wall(m, 4);
  const MapPointLedger::Point* wall =
      m.model().map_points().find(60);  // the one at (1.05, .05, .05)
  const MapPointLedger::Point* behind = m.model().map_points().find(9999);
  REQUIRE(wall != nullptr);
  REQUIRE(behind != nullptr);
  REQUIRE(wall->believed);
  REQUIRE(behind->believed);
  CHECK(rays == 121);  // the wall's rays, not the one through the wall
  OcKey between;
  REQUIRE(m.map().grid().coord_to_key(1.55, 0.05, 0.05, between));
  CHECK_FALSE(m.map().logodds(between).has_value());
  // The point behind the wall is one witness against the wall point, however often re-detected.
  CHECK(m.model().counts(*wall).c == 1);

  // While the mixture has found no wrong class (the library's model here) every ray is cast.
  Mapper<RobustModel> undecided(0.1);
  CHECK(behind_the_wall(undecided, 4) == 122);
  CHECK_FALSE(undecided.model().wrong_class_found());

  // The variants: the ray cast and the space behind the wall carved; one see-through a keyframe.
  Mapper<DecidingModel<RaysThroughBelieved>> through(0.1);
  CHECK(behind_the_wall(through, 4) == 122);
  REQUIRE(through.map().logodds(between).has_value());
  CHECK_FALSE(through.map().is_occupied(*through.map().logodds(between)));
  Mapper<DecidingModel<SeeThroughPerKeyframe>> per_keyframe(0.1);
  behind_the_wall(per_keyframe, 4);
  const auto* seen = per_keyframe.model().map_points().find(60);
  REQUIRE(seen != nullptr);
  CHECK(per_keyframe.model().counts(*seen).c == 4);
}

TEST_CASE("robust model: one keyframe's endpoints in a voxel add their mean") {
  RobustModelParams params;
  params.knn.k = 50;
  Mapper<RobustModel> m(0.1, RobustModel(params));
  const Point3d origin{0.05, 0.05, 0.05};
  const std::vector<Point3d> pts{{2.01, 0.05, 0.05}, {2.08, 0.06, 0.04}};  // one voxel
  const std::vector<std::uint64_t> ids{1, 2};
  for (int i = 0; i < 3; ++i) m.insert_keyframe(origin, pts, ids);
  OcKey k;
  REQUIRE(m.map().grid().point_to_key(pts[0], k));
  // Per keyframe: the mean of the two endpoints' ratings, as one endpoint would add, also for
  // the evidence added when the points became believed.
  CHECK(*m.map().logodds(k) == doctest::Approx(3 * logodds(0.65)).epsilon(1e-5));
  CHECK(m.model().map_points().find(1)->shares == doctest::Approx(1.5));
}

TEST_CASE("robust model: the SLAM system's counters reach the model") {
  Mapper<RobustModel> m(0.1);
  const std::vector<Point3d> pts{{2.05, 0.05, 0.05}, {2.05, 0.55, 0.05}};
  const std::vector<std::uint64_t> ids{7, 8};
  const std::vector<PointEvidence> ev{{3, 4, 2}, {0, 0, 9}};
  m.insert_keyframe(Point3d{0, 0, 0}, pts, ids, ev);
  const MapPointLedger::Point* p = m.model().map_points().find(7);
  REQUIRE(p != nullptr);
  CHECK(p->slam.found == 3);
  CHECK(p->slam.visible == 4);
  CHECK(m.model().counts(*p).f == 3);
  CHECK(m.model().counts(*p).v == 4);
  CHECK(m.model().counts(*p).d == 2);  // the SLAM system's two observations
  const MapPointLedger::Point* q = m.model().map_points().find(8);
  CHECK(m.model().counts(*q).v == 0);  // no ratio given: no found/visible term
  CHECK(m.model().counts(*q).d == 9);
  CHECK_THROWS_AS(m.insert_keyframe(Point3d{0, 0, 0}, pts, ids, std::vector<PointEvidence>(1)),
                  std::invalid_argument);
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
    if (!r || std::fabs(*r - v) > 1e-5f) ++differ;
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
  std::vector<std::uint64_t> ids(pts.size());
  for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = 7 + i;
  Mapper<RobustModel> robust(0.1);
  const KeyframeStats ks = robust.insert_keyframe(Point3d{0, 0, 0}, pts);
  CHECK(ks.rated == pts.size());
  CHECK(ks.rays == pts.size());
  CHECK(ks.tracker.added == 0);
  CHECK(robust.tracker().size() == 0);  // the model rates them without it
  CHECK(robust.model().map_points().size() == 0);
  CHECK(robust.map().count_voxels().occupied > 100);
  // a sequence either always or never gives ids, both ways round
  CHECK_THROWS_WITH_AS(robust.insert_keyframe(Point3d{0, 0, 0}, pts, ids),
                       doctest::Contains("mixed"), std::invalid_argument);
  Mapper<RobustModel> with_ids(0.1);
  with_ids.insert_keyframe(Point3d{0, 0, 0}, pts, ids);
  CHECK(with_ids.tracker().size() == pts.size());
  CHECK_THROWS_AS(with_ids.insert_keyframe(Point3d{0, 0, 0}, pts), std::invalid_argument);
  // the k-NN model keeps the cloud of keyframes without ids (its s needs it)
  Mapper<KnnModel> knn(0.1);
  knn.insert_keyframe(Point3d{0, 0, 0}, pts);
  CHECK(knn.tracker().size() == pts.size());
}

TEST_CASE("robust model: invalid parameters are refused") {
  RobustModelParams p;
  p.margin_scale = -1;
  CHECK_THROWS_AS(RobustModel{p}, std::invalid_argument);
  p = {};
  p.p_hit = 0.5;
  CHECK_THROWS_AS(RobustModel{p}, std::invalid_argument);
  p = {};
  p.knn.p_w = 0.95;
  CHECK_THROWS_AS(RobustModel{p}, std::invalid_argument);
}
