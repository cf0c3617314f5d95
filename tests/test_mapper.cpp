// Mapper (Alg. 3): the OctoMap model through the Mapper is ScanInserter's insertion (itself
// checked against liboctomap in test_octomap_reference.cpp); the k-NN model equals an oracle
// written from the paper: brute-force s_p over the union of the keyframes (knn_truth.hpp), the
// distribution by two passes, eq 13-15 per endpoint with erfc, rays key by key
// (compute_ray_keys), the map updated voxel by voxel. It shares the DDA, the max-range
// truncation, the map's update rule and kMinProb with the code under test, and applies eq 15's
// per-node sum as one update (Alg. 3 line 5 adds per point; the two differ only where clamping
// cuts in between).

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <type_traits>
#include <utility>
#include <vector>

#include <knnocc/mapper.hpp>
#include <knnocc/raycast/dda.hpp>
#include <knnocc/sensor/knn_model.hpp>
#include <knnocc/sensor/robust_model.hpp>

#include "knn_oracle.hpp"
#include "test_support.hpp"

using namespace knnocc;

using knnocc::test::voxel_values;

namespace {

struct Keyframe {
  Point3d origin;
  std::vector<Point3d> points;
  std::vector<std::uint64_t> ids;  // empty: no ids
};

// A sparse noisy "object" seen from a circle of poses: surface points on a sphere with noise,
// a few gross outliers; with ids, map points are re-observed by later keyframes.
std::vector<Keyframe> random_sequence(test::Rng& rng, bool with_ids, std::size_t frames) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.03);
  std::vector<Point3d> surface;
  for (int i = 0; i < 400; ++i) {
    double x, y, z, n;
    do {
      x = u(rng), y = u(rng), z = u(rng);
      n = std::sqrt(x * x + y * y + z * z);
    } while (n < 0.1);
    surface.push_back({1.0 * x / n, 1.0 * y / n, 0.7 * z / n + 1.0});
  }
  std::vector<Keyframe> kfs;
  for (std::size_t f = 0; f < frames; ++f) {
    Keyframe kf;
    const double a = 2 * M_PI * static_cast<double>(f) / static_cast<double>(frames);
    kf.origin = {3.0 * std::cos(a), 3.0 * std::sin(a), 1.2};
    for (std::size_t i = 0; i < surface.size(); ++i) {
      const Point3d& s = surface[i];
      if (s.x * std::cos(a) + s.y * std::sin(a) < 0.1) continue;  // the visible side
      if (rng() % 3) continue;                                    // sparse
      kf.points.push_back({s.x + noise(rng), s.y + noise(rng), s.z + noise(rng)});
      if (with_ids) kf.ids.push_back(i);
    }
    for (int o = 0; o < 4; ++o) {  // wrong matches: anywhere between sensor and 2 m behind
      const double t = 0.3 + 1.2 * (u(rng) + 1.0);
      kf.points.push_back({kf.origin.x * (1 - t / 3) + 0.5 * u(rng),
                           kf.origin.y * (1 - t / 3) + 0.5 * u(rng), 1.0 + u(rng)});
      if (with_ids) kf.ids.push_back(100000 + f * 10 + static_cast<std::uint64_t>(o));
    }
    kfs.push_back(std::move(kf));
  }
  return kfs;
}

using ValueMap = std::map<std::uint64_t, float>;

// The paper, literally, with nothing shared with the Mapper but the map's update rule and the
// DDA (both tested against OctoMap elsewhere).
ValueMap knn_oracle(const std::vector<Keyframe>& kfs, double res, const KnnModelParams& p,
                    double max_range) {
  OccupancyMap<OcKey> map(res);
  test::Cloud cloud;
  std::uint64_t next_id = 0;
  const double phi_w = 0.5 * std::erfc(-p.w / std::sqrt(2.0));
  for (const Keyframe& kf : kfs) {
    const Point3f o{float(kf.origin.x), float(kf.origin.y), float(kf.origin.z)};
    auto in_range = [&](const Point3d& q) {
      const Point3f f{float(q.x), float(q.y), float(q.z)};
      return max_range < 0 || detail::octomap_norm(f.x - o.x, f.y - o.y, f.z - o.z) <= max_range;
    };
    std::vector<std::uint64_t> id_of(kf.points.size());
    for (std::size_t j = 0; j < kf.points.size(); ++j) {
      if (!in_range(kf.points[j])) continue;
      id_of[j] = kf.ids.empty() ? next_id++ : kf.ids[j];
      cloud.emplace(id_of[j], kf.points[j]);  // first position wins
    }
    const test::Truth t = test::brute_force(cloud, p.k, p.s_limit);
    std::map<std::uint64_t, double> occupied;  // key -> sum of logit(Prob) (eq 15)
    std::set<std::uint64_t> free;
    std::vector<OcKey> ray;
    for (std::size_t j = 0; j < kf.points.size(); ++j) {
      const Point3d& q = kf.points[j];
      const Point3f e{float(q.x), float(q.y), float(q.z)};
      if (!in_range(q)) {  // OctoMap's max range: the truncated ray, nothing occupied
        if (compute_ray_keys(map.grid(), o, truncate_ray(o, e, max_range), ray))
          for (const OcKey& k : ray) free.insert(k.pack());
        continue;
      }
      const double s = t.s.at(id_of[j]);
      double prob = p.p_w;
      if (t.n > 0) {
        const double cdf = std::isnan(s) ? 1.0
                           : t.sigma > 0 ? 0.5 * std::erfc(-(s - t.mean) / t.sigma / std::sqrt(2.0))
                           : s < t.mean  ? 0.0
                           : s > t.mean  ? 1.0
                                         : 0.5;
        prob = std::max(KnnModel::kMinProb, p.p_upper - cdf / phi_w * (p.p_upper - p.p_w));
      }
      OcKey k;
      REQUIRE(map.grid().point_to_key(e, k));
      occupied[k.pack()] += static_cast<double>(logodds(prob));
      if (std::log(prob / (1 - prob)) > std::log(p.p_w / (1 - p.p_w)) &&  // eq 14
          compute_ray_keys(map.grid(), o, e, ray))
        for (const OcKey& r : ray) free.insert(r.pack());
    }
    for (const std::uint64_t k : free)
      if (!occupied.count(k)) map.update(OcKey::unpack(k), logodds(p.p_free));
    for (const auto& [k, sum] : occupied) map.update(OcKey::unpack(k), static_cast<float>(sum));
  }
  return voxel_values(map);
}

// Same keys; values equal up to the rounding of the distribution (Welford vs two passes).
void expect_same(const ValueMap& got, const ValueMap& want) {
  REQUIRE(got.size() == want.size());
  std::size_t differ = 0;
  auto g = got.begin();
  for (auto w = want.begin(); w != want.end(); ++w, ++g) {
    REQUIRE(g->first == w->first);
    if (std::fabs(g->second - w->second) > 2e-5f) ++differ;
  }
  CHECK(differ == 0);
}

}  // namespace

TEST_CASE("mapper: the OctoMap model through the Mapper is ScanInserter's insertPointCloud") {
  test::Rng rng(7);
  for (const double max_range : {-1.0, 2.5}) {
    const auto kfs = random_sequence(rng, false, 6);
    Mapper<OctoMapModel> mapper(0.1, {}, MapperOptions{max_range, false, 1, {}});
    OccupancyMap<OcKey> reference(0.1);
    ScanInserter<OcKey> inserter(reference);
    for (const Keyframe& kf : kfs) {
      const KeyframeStats ks = mapper.insert_keyframe(kf.origin, kf.points);
      const ScanStats st = inserter.insert_point_cloud(kf.origin, kf.points, max_range);
      CHECK(ks.scan.occupied_voxels == st.occupied_voxels);
      CHECK(ks.scan.free_voxels == st.free_voxels);
    }
    CHECK(voxel_values(mapper.map()) == voxel_values(reference));
  }
}

TEST_CASE("mapper: the k-NN model equals the paper's Alg. 2 + Alg. 3 done by brute force") {
  test::Rng rng(11);
  for (const bool with_ids : {false, true})
    for (const std::size_t k : {1u, 4u, 10u}) {
      CAPTURE(with_ids);
      CAPTURE(k);
      KnnModelParams p;
      p.k = k;
      p.w = k == 4 ? 0.0 : 1.0;
      p.s_limit = k == 10 ? 0.3 : std::numeric_limits<double>::infinity();
      const double max_range = k == 4 ? 3.2 : -1.0;
      const auto kfs = random_sequence(rng, with_ids, 8);
      Mapper<KnnModel> mapper(0.1, KnnModel(p), MapperOptions{max_range, false, 1, {}});
      std::size_t rays = 0, rated = 0;
      for (const Keyframe& kf : kfs) {
        const KeyframeStats ks = mapper.insert_keyframe(kf.origin, kf.points, kf.ids);
        rays += ks.rays;
        rated += ks.rated;
      }
      CHECK(rays > 0);      // the scene has reliable endpoints ...
      CHECK(rays < rated);  // ... and unreliable ones
      expect_same(voxel_values(mapper.map()), knn_oracle(kfs, 0.1, p, max_range));
    }
}

TEST_CASE("mapper: eq 15 sums the endpoints of a voxel; unreliable endpoints free nothing") {
  KnnModelParams p;
  p.k = 1;
  p.w = 0.0;  // reliable iff s < mu
  Mapper<KnnModel> mapper(0.1, KnnModel(p));
  // Three tight pairs and one isolated point: s = 0.01 (x6) and 1.0 (x1 ... its neighbour is far).
  const std::vector<Point3d> pts = {{1.01, 0.01, 0.01}, {1.02, 0.01, 0.01},  {1.01, 0.51, 0.01},
                                    {1.02, 0.51, 0.01}, {1.01, -0.49, 0.01}, {1.02, -0.49, 0.01},
                                    {1.51, 2.01, 0.01}};
  const KeyframeStats ks = mapper.insert_keyframe(Point3d{0.01, 0.01, 0.01}, pts);
  CHECK(ks.rated == 7);
  CHECK(ks.rays == 6);
  const auto& map = mapper.map();
  const RunningNormal& d = mapper.tracker().distribution();
  CHECK(d.count() == 7);
  const KnnModel& model = mapper.model();
  const float pair = 2 * model.rate(0.01, d).logodds;  // both endpoints of a pair in one voxel
  OcKey k;
  REQUIRE(map.grid().coord_to_key(1.015, 0.01, 0.01, k));
  CHECK(*map.logodds(k) == doctest::Approx(pair).epsilon(1e-6));
  // The isolated endpoint: occupied evidence of its own, no free ray towards it.
  const double s_far = mapper.tracker().s(6);
  CHECK(s_far > d.mean());
  REQUIRE(map.grid().coord_to_key(1.51, 2.01, 0.01, k));
  CHECK(*map.logodds(k) == doctest::Approx(model.rate(s_far, d).logodds).epsilon(1e-6));
  REQUIRE(map.grid().coord_to_key(0.76, 1.01, 0.01, k));  // half way along its ray
  CHECK_FALSE(map.logodds(k).has_value());
  REQUIRE(map.grid().coord_to_key(0.51, 0.01, 0.01, k));  // half way to the first pair: free
  CHECK(*map.logodds(k) == doctest::Approx(logodds(0.4)));
}

TEST_CASE("mapper: the k-NN map does not depend on the thread count or the change-set API") {
  test::Rng rng(5);
  const auto kfs = random_sequence(rng, true, 6);
  KnnModelParams p;
  p.k = 5;
  Mapper<KnnModel> one(0.05, KnnModel(p), MapperOptions{-1.0, false, 1, {}});
  Mapper<KnnModel> three(0.05, KnnModel(p), MapperOptions{-1.0, false, 3, {}});
  Mapper<KnnModel> explicit_change(0.05, KnnModel(p));
  std::set<std::uint64_t> seen;
  for (const Keyframe& kf : kfs) {
    one.insert_keyframe(kf.origin, kf.points, kf.ids);
    three.insert_keyframe(kf.origin, kf.points, kf.ids);
    ChangeSet cs;  // what KeyframeUnion derives: first observations join
    for (std::size_t j = 0; j < kf.points.size(); ++j)
      if (seen.insert(kf.ids[j]).second) cs.added.push_back({kf.ids[j], kf.points[j]});
    explicit_change.insert_keyframe(kf.origin, kf.points, kf.ids, cs);
  }
  CHECK(voxel_values(one.map()) == voxel_values(three.map()));
  CHECK(voxel_values(one.map()) == voxel_values(explicit_change.map()));
  CHECK(one.tracker().size() == seen.size());
}

TEST_CASE("mapper: points beyond max_range stay out of the map cloud and carve a truncated ray") {
  Mapper<KnnModel> mapper(0.1, KnnModel(KnnModelParams{}), MapperOptions{2.0, false, 1, {}});
  std::vector<Point3d> pts;
  for (int i = 0; i < 30; ++i) pts.push_back({1.0 + 0.01 * i, 0.05, 0.05});
  pts.push_back({5.05, 1.05, 0.05});
  const KeyframeStats ks = mapper.insert_keyframe(Point3d{0.05, 0.05, 0.05}, pts);
  CHECK(mapper.tracker().size() == 30);
  CHECK(ks.scan.beyond_max_range == 1);
  OcKey k;
  REQUIRE(mapper.map().grid().coord_to_key(1.0, 0.25, 0.05, k));  // on the truncated ray
  CHECK(mapper.map().logodds(k).has_value());
  REQUIRE(mapper.map().grid().coord_to_key(5.05, 1.05, 0.05, k));
  CHECK_FALSE(mapper.map().logodds(k).has_value());
}

TEST_CASE("mapper: the two keyframe overloads are not mixed; the reserved id is refused") {
  const std::vector<Point3d> pts = {{1, 1, 1}, {2, 2, 2}};
  const std::vector<std::uint64_t> ids = {1, 2};
  {
    Mapper<KnnModel> m(0.1);
    m.insert_keyframe(Point3d{}, pts, ids);
    ChangeSet cs;
    CHECK_THROWS_AS(m.insert_keyframe(Point3d{}, pts, ids, cs), std::invalid_argument);
  }
  {
    Mapper<KnnModel> m(0.1);
    ChangeSet cs;
    cs.added = {{1, pts[0]}, {2, pts[1]}};
    m.insert_keyframe(Point3d{}, pts, ids, cs);
    CHECK_THROWS_AS(m.insert_keyframe(Point3d{}, pts, ids), std::invalid_argument);
    CHECK(m.tracker().size() == 2);
  }
  Mapper<KnnModel> m(0.1);
  CHECK_THROWS_AS(m.insert_keyframe(Point3d{}, pts, std::vector<std::uint64_t>{1, ~0ull}),
                  std::invalid_argument);
}

TEST_CASE("mapper: bad options are rejected") {
  CHECK_THROWS_AS(Mapper<KnnModel>(0.1, KnnModel{}, MapperOptions{-1.0, true, 1, {}}),
                  std::invalid_argument);
  CHECK_THROWS_AS(Mapper<OctoMapModel>(0.1, {}, MapperOptions{0.0, false, 1, {}}),
                  std::invalid_argument);
  CHECK_THROWS_AS(Mapper<OctoMapModel>(0.1, {}, MapperOptions{-1.0, false, 0, {}}),
                  std::invalid_argument);
  CHECK_THROWS_AS(Mapper<OctoMapModel>(0.0), std::invalid_argument);
  Mapper<KnnModel> m(0.1);
  const std::vector<Point3d> pts = {{1, 1, 1}, {2, 2, 2}};
  CHECK_THROWS_AS(m.insert_keyframe(Point3d{}, pts, std::vector<std::uint64_t>{1}),
                  std::invalid_argument);
}

namespace {

// Half the keyframes into one Mapper, which is then moved (constructed, then assigned over a
// Mapper that had mapped something else), the rest into the moved-to one: the map and the k-NN
// statistics equal a Mapper that was never moved.
template <class Model>
void check_moved_mapper_continues(const Model& model, bool with_ids) {
  static_assert(std::is_move_constructible_v<Mapper<Model>>);
  static_assert(std::is_move_assignable_v<Mapper<Model>>);
  test::Rng rng(23);
  const auto kfs = random_sequence(rng, with_ids, 10);
  auto insert = [&](Mapper<Model>& m, const Keyframe& kf) {
    if constexpr (Mapper<Model>::uses_map_cloud)
      m.insert_keyframe(kf.origin, kf.points, kf.ids);
    else
      m.insert_keyframe(kf.origin, kf.points);
  };
  Mapper<Model> still(0.1, model);
  Mapper<Model> first(0.1, model);
  for (std::size_t i = 0; i < kfs.size() / 2; ++i) {
    insert(still, kfs[i]);
    insert(first, kfs[i]);
  }
  Mapper<Model> second(std::move(first));
  Mapper<Model> third(0.2, model);
  insert(third, kfs.back());
  third = std::move(second);
  for (std::size_t i = kfs.size() / 2; i < kfs.size(); ++i) {
    insert(still, kfs[i]);
    insert(third, kfs[i]);
  }
  CHECK(third.map().grid().resolution() == 0.1);
  CHECK(voxel_values(third.map()) == voxel_values(still.map()));
  CHECK(third.map().num_voxels() > 100);
  if constexpr (Mapper<Model>::uses_map_cloud) {
    CHECK(third.tracker().size() == still.tracker().size());
    CHECK(third.tracker().mu() == still.tracker().mu());
  }
}

}  // namespace

TEST_CASE("mapper: a moved Mapper continues as one that never moved") {
  SUBCASE("OctoMap model") { check_moved_mapper_continues(OctoMapModel{}, false); }
  SUBCASE("k-NN model") { check_moved_mapper_continues(KnnModel{}, true); }
  SUBCASE("robust model") { check_moved_mapper_continues(RobustModel{}, true); }
}

TEST_CASE("mapper: one default k for the tracker and the k-NN model") {
  CHECK(kDefaultK == 8);
  CHECK(TrackerParams{}.k == kDefaultK);
  CHECK(KnnModelParams{}.k == kDefaultK);
  CHECK(KnnModel{}.tracker_params().k == kDefaultK);
  Mapper<KnnModel> m(0.1);
  CHECK(m.tracker().params().k == kDefaultK);
}
