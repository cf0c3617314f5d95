// The tree-scene simulator: deterministic per seed, ORB-SLAM-like map points, and the paper's
// qualitative result on it (the k-NN model keeps the wrong matches out of the map).

#include <doctest/doctest.h>

#include <cmath>
#include <map>
#include <set>
#include <utility>

#include <knnocc/eval/metrics.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/sensor/knn_model.hpp>
#include <knnocc/sim/tree_scene.hpp>

using namespace knnocc;

namespace {
bool same(const std::vector<Point3f>& a, const std::vector<Point3f>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (a[i].x != b[i].x || a[i].y != b[i].y || a[i].z != b[i].z) return false;
  return true;
}
}  // namespace

TEST_CASE("sim: a seed gives the same scene; map points keep their id and position") {
  sim::TreeSceneParams p;
  p.keyframes = 24;
  const auto a = sim::TreeScene(p).keyframes();
  const auto b = sim::TreeScene(p).keyframes();
  p.seed = 2;
  const auto c = sim::TreeScene(p).keyframes();
  REQUIRE(a.size() == 24);
  bool differs = false;
  std::size_t points = 0, outliers = 0;
  std::map<std::uint64_t, Eigen::Vector3d> seen;
  std::size_t reobserved = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    CHECK(same(a[i].cloud.points, b[i].cloud.points));
    CHECK(a[i].cloud.ids == b[i].cloud.ids);
    differs = differs || !same(a[i].cloud.points, c[i].cloud.points);
    REQUIRE(a[i].cloud.ids.size() == a[i].cloud.points.size());
    points += a[i].cloud.points.size();
    outliers += a[i].outliers;
    const Eigen::Matrix3d R = a[i].pose.q.toRotationMatrix();
    CHECK(std::fabs(a[i].pose.q.norm() - 1.0) < 1e-12);
    CHECK(std::fabs(a[i].pose.t.head<2>().norm() - 3.5) < 0.5);  // on the circle
    for (std::size_t j = 0; j < a[i].cloud.points.size(); ++j) {
      const Point3f& q = a[i].cloud.points[j];
      CHECK(q.z > 0.0f);  // in front of the camera
      const Eigen::Vector3d w = R * Eigen::Vector3d(q.x, q.y, q.z) + a[i].pose.t;
      const std::uint64_t id = a[i].cloud.ids[j];
      auto [it, fresh] = seen.emplace(id, w);
      if (!fresh) {
        ++reobserved;
        CHECK((it->second - w).norm() < 1e-5);       // the same world position (float rounding)
        CHECK(id < sim::TreeScene::kOutlierIdBase);  // wrong matches are seen once
      }
    }
  }
  CHECK(differs);
  CHECK(points > 24 * 100);
  CHECK(reobserved > points / 2);  // map points are seen by several keyframes
  const double fraction = double(outliers) / double(points);
  CHECK(fraction > 0.05);
  CHECK(fraction < 0.11);
}

TEST_CASE("sim: the k-NN model keeps wrong matches out of the map (the paper's Table 1)") {
  for (const std::uint64_t seed : {1u, 2u}) {
    sim::TreeSceneParams p;
    p.seed = seed;
    sim::TreeScene scene(p);
    const auto kfs = scene.keyframes();
    Mapper<OctoMapModel> octo(0.1);
    Mapper<KnnModel> knn(0.1);
    sim::map_keyframes(octo, kfs, 4.0);
    sim::map_keyframes(knn, kfs, 4.0);
    const eval::Metrics mo = eval::evaluate(octo.map(), scene.reference());
    const eval::Metrics mk = eval::evaluate(knn.map(), scene.reference());
    CAPTURE(seed);
    CHECK(mo.irrelevant >= 30);                    // the OctoMap model invents nodes ...
    CHECK(mk.irrelevant * 10 <= mo.irrelevant);    // ... the k-NN model <= 10 % of them
    CHECK(mk.in_shell * 100 >= mo.in_shell * 97);  // and keeps the shell
    CHECK(mk.free_inside < mo.free_inside);        // fewer rays through the objects
    CHECK(mo.shell > 1200);
  }
}

TEST_CASE("sim: clustered, repeated and depth-dependent wrong matches") {
  sim::TreeSceneParams p;
  p.keyframes = 20;
  p.outlier_cluster = 6;
  p.outlier_repeat = 3;
  p.outliers = 0.1;
  const auto kfs = sim::TreeScene(p).keyframes();
  std::map<std::uint64_t, std::vector<std::size_t>> seen;  // outlier id -> keyframes
  std::map<std::uint64_t, Eigen::Vector3d> where;
  std::size_t wrong = 0, points = 0;
  for (std::size_t i = 0; i < kfs.size(); ++i) {
    const Eigen::Matrix3d R = kfs[i].pose.q.toRotationMatrix();
    std::size_t counted = 0;
    for (std::size_t j = 0; j < kfs[i].cloud.points.size(); ++j) {
      const std::uint64_t id = kfs[i].cloud.ids[j];
      ++points;
      if (id < sim::TreeScene::kOutlierIdBase) continue;
      ++counted;
      const Point3f& q = kfs[i].cloud.points[j];
      const Eigen::Vector3d w = R * Eigen::Vector3d(q.x, q.y, q.z) + kfs[i].pose.t;
      auto [it, fresh] = where.emplace(id, w);
      if (!fresh) CHECK((it->second - w).norm() < 1e-5);  // re-observed at the same position
      seen[id].push_back(i);
    }
    CHECK(counted == kfs[i].outliers);
    wrong += counted;
  }
  // Patches: ids come in runs of 6 created together, each within a few cm of the first.
  std::size_t patches = 0, repeated = 0;
  for (const auto& [id, kf] : seen) {
    const std::uint64_t first =
        sim::TreeScene::kOutlierIdBase + (id - sim::TreeScene::kOutlierIdBase) / 6 * 6;
    REQUIRE(where.count(first));
    CHECK((where[id] - where[first]).norm() < 0.3);  // same patch: near (depth scaled)
    CHECK(seen[first].front() == kf.front());        // created by the same keyframe
    CHECK(kf.size() <= 4);                           // first + up to 3 re-observations
    CHECK(kf.back() - kf.front() <= 3);              // by the following keyframes
    patches += id == first;
    repeated += kf.size() > 1;
  }
  CHECK(patches > 20);
  CHECK(repeated > seen.size() / 2);
  CHECK(wrong > points / 10);  // re-observations add to the 10 % created

  // Defaults: the scene is the one without the new parameters (same random sequence).
  sim::TreeSceneParams d;
  d.keyframes = 5;
  sim::TreeSceneParams e = d;
  e.repeat_prob = 0.5;  // only used with outlier_repeat > 0
  const auto a = sim::TreeScene(d).keyframes(), b = sim::TreeScene(e).keyframes();
  for (std::size_t i = 0; i < a.size(); ++i) CHECK(same(a[i].cloud.points, b[i].cloud.points));
}

TEST_CASE("sim: random_patches draws each patch's size and lifetime up to the maxima") {
  auto run = [](bool random) {
    sim::TreeSceneParams p;
    p.keyframes = 60;
    p.outlier_cluster = 8;
    p.outlier_repeat = 12;
    p.outliers = 0.1;
    p.random_patches = random;
    std::map<std::uint64_t, std::pair<std::size_t, std::size_t>> span;  // id -> first, last
    std::size_t created = 0, patches = 0, observations = 0;
    const auto kfs = sim::TreeScene(p).keyframes();
    for (std::size_t i = 0; i < kfs.size(); ++i) {
      patches += kfs[i].patches;
      for (const std::uint64_t id : kfs[i].cloud.ids) {
        if (id < sim::TreeScene::kOutlierIdBase) {
          ++observations;
          continue;
        }
        auto [it, fresh] = span.try_emplace(id, i, i);
        it->second.second = i;
        created += fresh;
        observations += fresh;
      }
    }
    std::set<std::size_t> spans;
    for (const auto& e : span) spans.insert(e.second.second - e.second.first);
    struct R {
      double mean_size, wrong_fraction;
      std::set<std::size_t> spans;
    };
    return R{double(created) / double(patches), double(created) / double(observations), spans};
  };
  const auto fixed = run(false), random = run(true);
  CHECK(fixed.mean_size == 8.0);
  CHECK(random.mean_size > 3.0);  // uniform over 1..8: 4.5
  CHECK(random.mean_size < 6.0);
  // The rate is divided by the mean size: `outliers` stays the fraction of wrong points.
  CHECK(random.wrong_fraction == doctest::Approx(0.1).epsilon(0.3));
  CHECK(fixed.wrong_fraction == doctest::Approx(0.1).epsilon(0.3));
  CHECK(*random.spans.rbegin() <= 12);
  CHECK(random.spans.size() >= 8);  // lifetimes drawn from 0..12
  CHECK(*fixed.spans.rbegin() <= 12);
}

TEST_CASE("sim: outliers grow with depth with outlier_depth_gain") {
  // Ground only: a wrong match at depth factor f on the ray to a ground point lies at world
  // height h = camera height * (1 - f), which gives back f and the true depth.
  auto far_over_near = [](double gain) {
    sim::TreeSceneParams p;
    p.keyframes = 30;
    p.outliers = 0.05;
    p.foliage_density = 0;
    p.pot_density = 0;
    p.ground_density = 40;
    p.outlier_depth_gain = gain;
    double n[2] = {0, 0}, w[2] = {0, 0};  // near (< 3 m), far (> 4.5 m)
    for (const auto& kf : sim::TreeScene(p).keyframes()) {
      const Eigen::Matrix3d R = kf.pose.q.toRotationMatrix();
      for (std::size_t j = 0; j < kf.cloud.points.size(); ++j) {
        const Point3f& q = kf.cloud.points[j];
        const bool wrong = kf.cloud.ids[j] >= sim::TreeScene::kOutlierIdBase;
        double depth = q.z;
        if (wrong) {
          const Eigen::Vector3d wp = R * Eigen::Vector3d(q.x, q.y, q.z) + kf.pose.t;
          depth = q.z / (1.0 - wp.z() / kf.pose.t.z());
        }
        const int bin = depth < 3.0 ? 0 : depth > 4.5 ? 1 : -1;
        if (bin < 0) continue;
        n[bin] += 1;
        w[bin] += wrong;
      }
    }
    REQUIRE(n[0] > 100);
    REQUIRE(n[1] > 100);
    return (w[1] / n[1]) / (w[0] / n[0]);
  };
  const double flat = far_over_near(0.0), grows = far_over_near(2.0);
  CHECK(flat < 1.5);
  CHECK(grows > 2.0);
}

TEST_CASE("sim: seen_once_fraction counts distinct ids one keyframe alone observes") {
  std::vector<sim::SimKeyframe> kfs(2);
  kfs[0].cloud.points = {{0, 0, 1}, {0, 0, 1}, {0, 0, 9}};
  kfs[0].cloud.ids = {1, 1, 2};  // 1 twice in one keyframe: still once
  kfs[1].cloud.points = {{0, 0, 1}, {0, 0, 2}};
  kfs[1].cloud.ids = {3, 2};
  CHECK(sim::seen_once_fraction(kfs, -1) == doctest::Approx(2.0 / 3.0));  // 1 and 3
  CHECK(sim::seen_once_fraction(kfs, 4.0) == doctest::Approx(1.0));       // 2 only once within 4 m
}
