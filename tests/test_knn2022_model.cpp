// Knn2022Model (the authors' 2022 model) against brute force: d by sorting every distance, the
// truncated normal CDF by numerical integration of the density, the running statistics by an
// exact two-pass computation over every d so far, and Mapper<Knn2022Model>'s map by the model's
// rules applied voxel by voxel with compute_ray_keys.

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <stdexcept>
#include <vector>

#include <knnocc/map/same_voxels.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/raycast/dda.hpp>
#include <knnocc/sensor/knn2022_model.hpp>

#include "test_support.hpp"

using namespace knnocc;

namespace {

// Mean distance to the k nearest other inner points, by sorting all distances; NaN for points
// that are not inner, +inf for an inner point alone.
std::vector<double> brute_distances(const Point3d& o, const std::vector<Point3d>& pts,
                                    std::size_t k, double inner) {
  std::vector<double> d(pts.size(), std::numeric_limits<double>::quiet_NaN());
  auto is_inner = [&](const Point3d& p) {
    return std::isfinite(p.x + p.y + p.z) && dist2(p, o) <= inner * inner;
  };
  for (std::size_t i = 0; i < pts.size(); ++i) {
    if (!is_inner(pts[i])) continue;
    std::vector<std::pair<double, std::size_t>> all;
    for (std::size_t j = 0; j < pts.size(); ++j)
      if (j != i && is_inner(pts[j])) all.push_back({dist2(pts[i], pts[j]), j});
    std::sort(all.begin(), all.end());
    const std::size_t m = std::min(k, all.size());
    double sum = 0;
    for (std::size_t j = 0; j < m; ++j) sum += std::sqrt(all[j].first);
    d[i] = m ? sum / double(m) : std::numeric_limits<double>::infinity();
  }
  return d;
}

// Integral of the N(mu, sigma) density over [a, b] (composite Simpson).
double integrate_density(double a, double b, double mu, double sigma) {
  if (b <= a) return 0.0;
  const int n = 20000;
  const double h = (b - a) / n;
  auto f = [&](double s) {
    return std::exp(-(s - mu) * (s - mu) / (2 * sigma * sigma)) /
           std::sqrt(2 * M_PI * sigma * sigma);
  };
  double sum = f(a) + f(b);
  for (int i = 1; i < n; ++i) sum += f(a + i * h) * (i % 2 ? 4 : 2);
  return sum * h / 3;
}

// A keyframe: a noisy surface patch within ~3 m, a few scattered points, some beyond 4 m.
std::vector<Point3d> random_keyframe(test::Rng& rng, std::size_t n) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Point3d> pts;
  for (std::size_t i = 0; i < n; ++i) {
    const double x = 2.5 + 0.02 * u(rng);
    pts.push_back({x, u(rng), 0.5 * u(rng)});
  }
  for (int i = 0; i < 8; ++i) pts.push_back({1.0 + 2.0 * (u(rng) + 1), 2 * u(rng), u(rng)});
  for (int i = 0; i < 10; ++i) pts.push_back({4.2 + 2 * (u(rng) + 1), u(rng), u(rng)});
  return pts;
}

}  // namespace

TEST_CASE("knn2022: d is the mean distance to the k nearest inner points of the keyframe") {
  test::Rng rng(3);
  const Point3d o{0.1, -0.2, 0.05};
  for (const std::size_t k : {1u, 4u, 8u, 300u}) {
    CAPTURE(k);
    Knn2022Params p;
    p.k = k;
    const Knn2022Model model(p);
    std::vector<Point3d> pts = random_keyframe(rng, 150);
    pts.push_back(pts[3]);  // a duplicate: distance 0 to its twin
    pts.push_back({std::nan(""), 0, 0});
    std::vector<double> got;
    model.distances(o, pts, got);
    const std::vector<double> want = brute_distances(o, pts, k, p.inner_range);
    REQUIRE(got.size() == want.size());
    std::size_t outer = 0;
    for (std::size_t i = 0; i < got.size(); ++i) {
      if (std::isnan(want[i])) {
        CHECK(std::isnan(got[i]));
        ++outer;
        continue;
      }
      CHECK(got[i] == doctest::Approx(want[i]).epsilon(1e-12));
    }
    CHECK(outer >= 11);
  }
  // One inner point alone: no neighbour, d = +inf.
  std::vector<double> d;
  Knn2022Model().distances(o, {{1, 0, 0}, {9, 0, 0}}, d);
  CHECK(std::isinf(d[0]));
  CHECK(std::isnan(d[1]));
}

TEST_CASE("knn2022: p(d) falls from p_near at 0 to p_far along the normal CDF truncated at 0") {
  for (const double mu : {0.05, 0.2}) {
    Knn2022Params p;
    p.fixed_statistics = true;
    p.mu = mu;
    p.sigma = 0.08;
    p.p_near = 0.85;
    p.p_far = 0.25;
    const Knn2022Model model(p);
    const double mass = integrate_density(0.0, mu + 14 * p.sigma, mu, p.sigma);
    double previous = 1.0;
    for (double d = 0.0; d < 0.8; d += 0.02) {
      const double f = integrate_density(0.0, d, mu, p.sigma) / mass;
      const double got = model.probability(d);
      CHECK(got == doctest::Approx(p.p_near - (p.p_near - p.p_far) * f).epsilon(1e-7));
      CHECK(got <= previous);
      previous = got;
    }
    CHECK(model.probability(0.0) == doctest::Approx(p.p_near).epsilon(1e-12));
    CHECK(model.probability(std::numeric_limits<double>::infinity()) == p.p_far);
  }
  // sigma 0: the step at mu.
  Knn2022Params p;
  p.fixed_statistics = true;
  p.mu = 0.1;
  const Knn2022Model flat(p);
  CHECK(flat.probability(0.05) == p.p_near);
  CHECK(flat.probability(0.2) == p.p_far);
  CHECK(flat.probability(0.1) == doctest::Approx((p.p_near + p.p_far) / 2));
  // Online without any d yet: p_far.
  CHECK(Knn2022Model().probability(0.1) == Knn2022Params{}.p_far);
}

TEST_CASE("knn2022: online statistics are those of every inner d so far, this keyframe's first") {
  test::Rng rng(5);
  Knn2022Model model;
  std::vector<double> all;
  std::vector<LayeredRating> ratings;
  const Point3d o{0, 0, 0};
  for (int kf = 0; kf < 4; ++kf) {
    const std::vector<Point3d> pts = random_keyframe(rng, 60 + 20 * kf);
    for (const double d : brute_distances(o, pts, model.params().k, model.params().inner_range))
      if (std::isfinite(d)) all.push_back(d);
    model.rate_cloud(o, pts, ratings);
    RunningNormal exact;
    exact.recompute(all);
    CHECK(model.distribution().count() == all.size());
    CHECK(model.mu() == doctest::Approx(exact.mean()).epsilon(1e-12));
    CHECK(model.sigma() == doctest::Approx(exact.sigma()).epsilon(1e-9));
    // The ratings use the statistics that include this keyframe.
    const std::vector<double> d = brute_distances(o, pts, model.params().k, 4.0);
    for (std::size_t j = 0; j < pts.size(); ++j) {
      if (std::isnan(d[j])) {
        CHECK_FALSE(ratings[j].hit);
        CHECK(ratings[j].ray == RayLayer::weak);
        continue;
      }
      CHECK(ratings[j].hit);
      CHECK(ratings[j].ray == RayLayer::strong);
      CHECK(ratings[j].logodds == doctest::Approx(logodds(model.probability(d[j]))));
    }
  }
}

TEST_CASE("knn2022: Mapper's map is the model's rules applied voxel by voxel") {
  test::Rng rng(9);
  for (const bool fixed : {false, true}) {
    CAPTURE(fixed);
    Knn2022Params p;  // not the defaults: a strong p_far, so some voxels' sums are negative
    p.k = 8;
    p.p_near = 0.9;
    p.p_far = 0.25;
    p.fixed_statistics = fixed;
    p.mu = 0.08;
    p.sigma = 0.05;
    Mapper<Knn2022Model> mapper(0.1, Knn2022Model(p));
    Knn2022Model rules(p);  // rates the same keyframes for the oracle
    OccupancyMap<OcKey> want(0.1);
    const RayLayers layers = rules.ray_layers();
    std::size_t negative_sums = 0;
    for (int kf = 0; kf < 5; ++kf) {
      const Point3d o{0.3 * kf, 0.1, 0.0};
      std::vector<Point3d> pts = random_keyframe(rng, 120);
      for (Point3d& q : pts) q.x += o.x;
      std::vector<LayeredRating> r;
      rules.rate_cloud(o, pts, r);
      const KeyframeStats ks = mapper.insert_keyframe(o, pts);
      CHECK(ks.rated == 120 + std::count_if(pts.begin() + 120, pts.end(),
                                            [&](const Point3d& q) { return dist2(q, o) <= 16.0; }));
      // The oracle: hits summed per voxel, then strong rays, then weak rays cut at 4 m.
      std::map<std::uint64_t, double> hits;
      std::set<std::uint64_t> strong, weak;
      std::vector<OcKey> ray;
      const Point3f of = detail::to_point3f(o);
      for (std::size_t j = 0; j < pts.size(); ++j) {
        const Point3f q = detail::to_point3f(pts[j]);
        OcKey k;
        REQUIRE(want.grid().point_to_key(q, k));
        if (r[j].hit) hits[k.pack()] += r[j].logodds;
        const bool cut = r[j].ray == RayLayer::weak &&
                         detail::octomap_norm(q.x - of.x, q.y - of.y, q.z - of.z) > 4.0;
        const Point3f end = cut ? truncate_ray(of, q, 4.0) : q;
        REQUIRE(compute_ray_keys(want.grid(), of, end, ray));
        for (const OcKey& key : ray) (r[j].hit ? strong : weak).insert(key.pack());
      }
      for (const auto& [k, sum] : hits) {
        want.update(OcKey::unpack(k), static_cast<float>(sum));
        negative_sums += sum < 0;
      }
      for (const auto k : strong)
        if (!hits.count(k)) want.update(OcKey::unpack(k), layers.strong_miss);
      for (const auto k : weak)
        if (!hits.count(k) && !strong.count(k)) want.update(OcKey::unpack(k), layers.weak_miss);
    }
    CHECK(want.num_voxels() > 2000);
    CHECK(same_voxels(mapper.map(), want));
    // Voxels holding only far-spread points lose probability (p_far < 0.5).
    CHECK(negative_sums > 0);
  }
}

TEST_CASE("knn2022: bad parameters are rejected, discretize too") {
  auto bad = [](auto change) {
    Knn2022Params p;
    change(p);
    CHECK_THROWS_AS(Knn2022Model{p}, std::invalid_argument);
  };
  bad([](Knn2022Params& p) { p.k = 0; });
  bad([](Knn2022Params& p) { p.inner_range = 0; });
  bad([](Knn2022Params& p) { p.p_far = 0.98; });  // above p_near
  bad([](Knn2022Params& p) { p.p_near = 1.0; });
  bad([](Knn2022Params& p) { p.p_miss = 0.5; });
  bad([](Knn2022Params& p) { p.p_miss_outer = 0.3; });  // stronger than p_miss
  bad([](Knn2022Params& p) {
    p.fixed_statistics = true;
    p.sigma = -1;
  });
  MapperOptions mo;
  mo.discretize = true;
  CHECK_THROWS_AS((Mapper<Knn2022Model>(0.1, Knn2022Model{}, mo)), std::invalid_argument);
}
