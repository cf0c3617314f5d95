// The tree-scene simulator: deterministic per seed, ORB-SLAM-like map points, and the paper's
// qualitative result on it (the k-NN model keeps the wrong matches out of the map).

#include <doctest/doctest.h>

#include <cmath>
#include <map>

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
