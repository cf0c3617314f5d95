// The bad-input matrix (docs/reliability.md, "Defined behaviour on bad data"), through the public
// Mapper with both sensor models: each row's defined behaviour, asserted.

#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <vector>

#include <knnocc/io/trajectory.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/sensor/knn_model.hpp>
#include <knnocc/sensor/robust_model.hpp>

#include "test_support.hpp"

using namespace knnocc;

using knnocc::test::voxel_values;

namespace {

// A small surface patch: every point has close neighbours.
std::vector<Point3d> patch(int n = 40) {
  std::vector<Point3d> pts;
  for (int i = 0; i < n; ++i) pts.push_back({2.0 + 0.03 * (i % 8), 0.4 + 0.03 * (i / 8), 0.25});
  return pts;
}

const double kInf = std::numeric_limits<double>::infinity();
const double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace

TEST_CASE_TEMPLATE("bad_input: NaN/Inf and huge points are skipped and counted, the map untouched",
                   Model, OctoMapModel, KnnModel) {
  const std::vector<Point3d> good = patch();
  std::vector<Point3d> bad = good;
  bad.insert(bad.begin() + 3, {kNaN, 0, 0});
  bad.insert(bad.begin() + 7, {0, kInf, 1});
  bad.push_back({-kInf, -kInf, -kInf});
  bad.push_back({1e300, 0, 0});  // finite, beyond float: +inf after rounding, no UB
  Mapper<Model> clean(0.1), dirty(0.1);
  clean.insert_keyframe(Point3d{0, 0, 0.2}, good);
  const KeyframeStats ks = dirty.insert_keyframe(Point3d{0, 0, 0.2}, bad);
  CHECK(ks.scan.points == bad.size());
  CHECK(ks.scan.nonfinite == 4);
  CHECK(voxel_values(dirty.map()) == voxel_values(clean.map()));
  if constexpr (Mapper<Model>::uses_map_cloud) CHECK(dirty.tracker().size() == good.size());
}

TEST_CASE_TEMPLATE("bad_input: points outside the key range are skipped and counted", Model,
                   OctoMapModel, KnnModel) {
  const std::vector<Point3d> good = patch();
  std::vector<Point3d> bad = good;
  bad.push_back({5000.0, 0, 0});  // 16-bit keys at 0.1 m reach +-3276.8 m
  bad.push_back({0, -4000.0, 0});
  Mapper<Model> clean(0.1), dirty(0.1);
  clean.insert_keyframe(Point3d{0, 0, 0.2}, good);
  const KeyframeStats ks = dirty.insert_keyframe(Point3d{0, 0, 0.2}, bad);
  CHECK(ks.scan.out_of_range == 2);
  CHECK(voxel_values(dirty.map()) == voxel_values(clean.map()));
  if constexpr (Mapper<Model>::uses_map_cloud) CHECK(dirty.tracker().size() == good.size());
  // The same points fit WideKey maps (21 bits: +-104 km at 0.1 m).
  Mapper<Model, WideKey> wide(0.1);
  CHECK(wide.insert_keyframe(Point3d{0, 0, 0.2}, bad).scan.out_of_range == 0);
}

TEST_CASE_TEMPLATE("bad_input: an empty cloud is a no-op", Model, OctoMapModel, KnnModel) {
  Mapper<Model> m(0.1);
  const KeyframeStats ks = m.insert_keyframe(Point3d{0, 0, 0}, std::vector<Point3d>{});
  CHECK(ks.scan.points == 0);
  CHECK(m.map().empty());
  m.insert_keyframe(Point3d{0, 0, 0.2}, patch());
  const auto before = voxel_values(m.map());
  m.insert_keyframe(Point3d{0, 0, 0}, std::vector<Point3d>{});
  CHECK(voxel_values(m.map()) == before);
}

TEST_CASE("bad_input: duplicate points (s = 0, sigma = 0) get the defined sigma = 0 rating") {
  KnnModelParams p;  // w = 0: Prob(s = mu) = P_u - (P_u - P_w) / (2 Phi(0)) = P_w
  Mapper<KnnModel> m(0.1, KnnModel(p));
  const std::vector<Point3d> same(20, Point3d{1.05, 0.05, 0.05});
  const KeyframeStats ks = m.insert_keyframe(Point3d{0.05, 0.05, 0.05}, same);
  CHECK(m.tracker().mu() == 0.0);
  CHECK(m.tracker().sigma() == 0.0);
  CHECK(ks.rays == 0);  // Prob == P_w is not above P_w (eq 14)
  CHECK(m.map().num_voxels() == 1);
  OcKey k;
  REQUIRE(m.map().grid().coord_to_key(1.05, 0.05, 0.05, k));
  CHECK(*m.map().logodds(k) == m.map().params().clamp_max);  // 20 x logit(P_w), clamped
}

TEST_CASE("bad_input: k >= cloud size gives N = 0: weak occupied evidence and no free rays") {
  KnnModelParams p;
  p.k = 8;
  Mapper<KnnModel> m(0.1, KnnModel(p));
  const std::vector<Point3d> few = {{1.05, 0.05, 0.05}, {1.05, 0.35, 0.05}, {1.05, 0.65, 0.05}};
  const KeyframeStats ks = m.insert_keyframe(Point3d{0.05, 0.05, 0.05}, few);
  CHECK(m.tracker().N() == 0);
  CHECK(ks.unrated == 3);
  CHECK(ks.rays == 0);
  CHECK(m.map().num_voxels() == 3);
  m.map().for_each_voxel([&](const OcKey&, float v) { CHECK(v == logodds(p.p_w)); });
}

TEST_CASE_TEMPLATE("bad_input: an endpoint in the sensor's own voxel is occupied, casts nothing",
                   Model, OctoMapModel, KnnModel) {
  // Every endpoint in the origin's voxel: that voxel is the whole map (no ray is cast).
  std::vector<Point3d> pts;
  for (int i = 0; i < 12; ++i) pts.push_back({0.01 + 0.007 * i, 0.03, 0.21 + 0.005 * (i % 3)});
  Mapper<Model> m(0.1);
  m.insert_keyframe(Point3d{0.05, 0.05, 0.25}, pts);
  CHECK(m.map().num_voxels() == 1);
  OcKey k;
  REQUIRE(m.map().grid().coord_to_key(0.05, 0.05, 0.25, k));
  REQUIRE(m.map().logodds(k).has_value());
  if constexpr (!Mapper<Model>::uses_map_cloud) CHECK(*m.map().is_occupied(k));
}

TEST_CASE("bad_input: max range 0 or NaN is rejected, negative means no limit") {
  CHECK_THROWS_AS(Mapper<KnnModel>(0.1, KnnModel{}, MapperOptions{0.0, false, 1, {}}),
                  std::invalid_argument);
  CHECK_THROWS_AS(Mapper<OctoMapModel>(0.1, {}, MapperOptions{kNaN, false, 1, {}}),
                  std::invalid_argument);
  Mapper<OctoMapModel> unlimited(0.1, {}, MapperOptions{-5.0, false, 1, {}});
  const KeyframeStats ks = unlimited.insert_keyframe(Point3d{0, 0, 0}, patch());
  CHECK(ks.scan.beyond_max_range == 0);
}

TEST_CASE("bad_input: resolution <= 0, NaN, Inf, absurdly small or large is a clear error") {
  // 1e35: 32768 voxels of it pass float's range, so no voxel centre could be a float point.
  for (const double r : {0.0, -0.1, kNaN, kInf, 1e-7, 1e-320, 1e35, 1e308}) {
    CAPTURE(r);
    try {
      OccupancyMap<OcKey> map(r);
      FAIL("accepted");
    } catch (const std::invalid_argument& e) {
      CHECK(std::string(e.what()).find("resolution") != std::string::npos);
    }
  }
  CHECK_NOTHROW(OccupancyMap<OcKey>(1e-6));
  CHECK_NOTHROW(OccupancyMap<OcKey>(1e34));
  CHECK_THROWS_AS(OccupancyMap<WideKey>(1e34), std::invalid_argument);  // 64x the keys
}

TEST_CASE("bad_input: a map-point id twice in one keyframe is an error, nothing changed") {
  const std::vector<Point3d> pts = {{1, 0, 0}, {1, 0.5, 0}, {1, 1, 0}};
  const std::vector<std::uint64_t> twice = {7, 8, 7}, once = {7, 8, 9};
  auto refused = [&](auto& mapper) {
    CHECK_THROWS_WITH_AS(mapper.insert_keyframe(Point3d{0, 0, 0}, pts, twice),
                         doctest::Contains("map-point id 7 appears twice in one keyframe"),
                         std::invalid_argument);
    CHECK(mapper.map().empty());
    CHECK_NOTHROW(mapper.insert_keyframe(Point3d{0, 0, 0}, pts, once));
  };
  Mapper<KnnModel> knn(0.1);
  refused(knn);
  Mapper<RobustModel> robust(0.1);
  refused(robust);
  KeyframeUnion u;
  CHECK_THROWS_WITH_AS(u.add(pts, twice), doctest::Contains("map-point id 7 appears twice"),
                       std::invalid_argument);
  // The OctoMap model takes no map points: it ignores ids, repeated or not.
  Mapper<OctoMapModel> octomap(0.1);
  CHECK(octomap.insert_keyframe(Point3d{0, 0, 0}, pts, twice).scan.points == 3);
}

TEST_CASE("bad_input: a pose quaternion off unit length is normalised (<= 1e-3) or rejected") {
  const auto dir = test::scratch_dir("bad_input");
  const std::string ok = (dir / "slightly_off.txt").string(), bad = (dir / "off.txt").string();
  std::FILE* f = std::fopen(ok.c_str(), "w");
  std::fputs("0 1 2 3 0 0 0.7072 0.7072\n", f);  // norm 1.00013: four-decimal rounding
  std::fclose(f);
  const auto poses = io::read_poses(ok);
  REQUIRE(poses.size() == 1);
  CHECK(std::fabs(poses[0].q.norm() - 1.0) < 1e-12);
  f = std::fopen(bad.c_str(), "w");
  std::fputs("0 1 2 3 0 0 0 2\n", f);  // norm 2: a column mix-up
  std::fclose(f);
  try {
    io::read_poses(bad);
    FAIL("accepted");
  } catch (const io::Error& e) {
    CHECK(std::string(e.what()).find("quaternion norm 2 is not 1") != std::string::npos);
  }
}

TEST_CASE("bad_input: a NaN sensor origin inserts nothing, not even into the map cloud") {
  for (const double max_range : {-1.0, 10.0}) {
    Mapper<KnnModel> m(0.1, KnnModel{}, MapperOptions{max_range, false, 1, {}});
    const KeyframeStats ks = m.insert_keyframe(Point3d{kNaN, 0, 0}, patch());
    CHECK_FALSE(ks.scan.origin_valid);
    CHECK(ks.scan.points == patch().size());
    CHECK(ks.rated == 0);
    CHECK(m.map().empty());
    CHECK(m.tracker().size() == 0);
  }
}
