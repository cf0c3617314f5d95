// The OctoMap model against liboctomap itself (when found) and against the reference counts of
// ../shared/data/README.md: the same occupied and free finest-level voxels, the same log-odds.
#include <doctest/doctest.h>

#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include <knnocc/insertion/scan_inserter.hpp>
#include <knnocc/io/sequence.hpp>
#include <knnocc/io/xyz.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/raycast/cast_ray.hpp>

#include "test_support.hpp"

#if KNNOCC_HAVE_OCTOMAP
#include <octomap/OcTree.h>

#include "octomap_oracle.hpp"
#endif

using knnocc::OccupancyMap;
using knnocc::OcKey;
using knnocc::Point3f;

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

using knnocc::test::Scan;

std::vector<Scan> tum_scans() {
  std::vector<Scan> scans;
  const std::string dir = knnocc::test::data_path("tum_fr2_pioneer_slam2");
  if (dir.empty()) return scans;
  const auto seq = knnocc::io::Sequence::open(dir);
  for (std::size_t i = 0; i < seq.size(); ++i) {
    Scan s;
    knnocc::io::transform_to_world(seq.pose(i), seq.load_cloud(i).points, s.points);
    const auto& t = seq.pose(i).t;
    s.origin = Point3f{float(t.x()), float(t.y()), float(t.z())};
    scans.push_back(std::move(s));
  }
  return scans;
}

knnocc::VoxelCounts insert_all(OccupancyMap<OcKey>& map, const std::vector<Scan>& scans,
                               double max_range = -1.0, bool discretize = false) {
  knnocc::ScanInserter<OcKey> inserter(map);
  const auto t0 = std::chrono::steady_clock::now();
  for (const auto& s : scans)
    inserter.insert_point_cloud(s.origin, s.points, max_range, discretize);
  MESSAGE("knnocc inserted " << scans.size() << " scan(s) in " << seconds_since(t0) << " s");
  return map.count_voxels();
}

#if KNNOCC_HAVE_OCTOMAP
// Every leaf of the octree (pruned or not) expands to finest voxels that our map must hold with
// the same value; equal totals then mean neither map has a voxel the other lacks.
void expect_same_map(const OccupancyMap<OcKey>& ours, const octomap::OcTree& tree) {
  std::size_t finest = 0, occupied = 0, mismatched = 0, missing = 0;
  float worst = 0.0f;
  knnocc::test::for_each_octomap_voxel(tree, [&](const OcKey& k, const octomap::OcTreeNode& leaf) {
    ++finest;
    occupied += tree.isNodeOccupied(leaf);
    const auto got = ours.logodds(k);
    if (!got) {
      ++missing;
      return;
    }
    const float diff = std::fabs(*got - leaf.getLogOdds());
    worst = std::max(worst, diff);
    mismatched += diff > 1e-5f;
  });
  const auto counts = ours.count_voxels();
  MESSAGE("liboctomap finest voxels: " << occupied << " occupied, " << finest - occupied
                                       << " free; knnocc: " << counts.occupied << " / "
                                       << counts.free << "; max |dlogodds| " << worst);
  CHECK(missing == 0);
  CHECK(mismatched == 0);
  CHECK(ours.num_voxels() == finest);
  CHECK(counts.occupied == occupied);
}

void octomap_insert(octomap::OcTree& tree, const std::vector<Scan>& scans, double max_range = -1.0,
                    bool discretize = false) {
  const auto t0 = std::chrono::steady_clock::now();
  for (const auto& s : scans) {
    octomap::Pointcloud pc;
    pc.reserve(s.points.size());
    for (const auto& p : s.points) pc.push_back(p.x, p.y, p.z);
    tree.insertPointCloud(pc, octomap::point3d(s.origin.x, s.origin.y, s.origin.z), max_range,
                          false, discretize);
  }
  MESSAGE("liboctomap inserted " << scans.size() << " scan(s) in " << seconds_since(t0) << " s");
}
#endif

}  // namespace

TEST_CASE("octomap_reference.fr079_scan") {
  std::vector<Scan> scans(1);
  scans[0].points = knnocc::test::scan_dat_points_or_skip();
  if (scans[0].points.empty()) return;
  REQUIRE(scans[0].points.size() == 88206);
  struct Case {
    double res;
    std::size_t occupied, free;  // liboctomap 1.9.7, from ../shared/data/README.md
  };
  for (const Case c : {Case{0.1, 23537, 794069}, Case{0.05, 40568, 3855241}}) {
    CAPTURE(c.res);
    OccupancyMap<OcKey> map(c.res);
    const auto counts = insert_all(map, scans);
    CHECK(counts.occupied == c.occupied);
    CHECK(counts.free == c.free);
#if KNNOCC_HAVE_OCTOMAP
    octomap::OcTree tree(c.res);
    octomap_insert(tree, scans);
    expect_same_map(map, tree);
#endif
  }
}

TEST_CASE("octomap_reference.tum_sequence") {
  const auto scans = tum_scans();
  if (scans.empty()) {
    knnocc::test::skip("skipped: ../shared/data/tum_fr2_pioneer_slam2 not available");
    return;
  }
  REQUIRE(scans.size() == 10);
  OccupancyMap<OcKey> map(0.05);
  const auto counts = insert_all(map, scans);
  CHECK(counts.occupied > 0);
#if KNNOCC_HAVE_OCTOMAP
  octomap::OcTree tree(0.05);
  octomap_insert(tree, scans);
  expect_same_map(map, tree);
#else
  knnocc::test::skip("liboctomap not found: only the knnocc side ran");
#endif
}

#if KNNOCC_HAVE_OCTOMAP
TEST_CASE("octomap_reference.random_scenes_max_range_discretize") {
  knnocc::test::Rng rng(1234);
  std::uniform_real_distribution<float> u(-6.f, 6.f), small(-0.3f, 0.3f);
  for (int trial = 0; trial < 8; ++trial) {
    const double res = trial % 2 ? 0.1 : 0.07;
    const double max_range = trial % 4 < 2 ? 3.5 : -1.0;
    const bool discretize = trial >= 4;
    CAPTURE(trial);
    std::vector<Scan> scans(5);
    for (auto& s : scans) {
      s.origin = Point3f{small(rng), small(rng), small(rng)};
      for (int i = 0; i < 3000; ++i) s.points.push_back({u(rng), u(rng), u(rng) * 0.4f});
    }
    OccupancyMap<OcKey> map(res);
    insert_all(map, scans, max_range, discretize);
    octomap::OcTree tree(res);
    octomap_insert(tree, scans, max_range, discretize);
    expect_same_map(map, tree);
  }
}

TEST_CASE("octomap_reference.hit_miss_and_clamping_parameters") {
  // knnocc map --prob-hit --prob-miss --clamp: the Mapper with OctoMapModel::from_probabilities
  // and OccupancyParams, against liboctomap's setProbHit/Miss and setClampingThresMin/Max. Scans
  // from nearby origins of points on a 0.5 m lattice reach both clamping bounds.
  knnocc::test::Rng rng(35);
  std::uniform_int_distribution<int> u(-8, 8);
  std::uniform_real_distribution<float> small(-0.2f, 0.2f);
  std::vector<Scan> scans(12);
  for (auto& s : scans) {
    s.origin = Point3f{small(rng), small(rng), small(rng)};
    for (int i = 0; i < 1500; ++i)
      s.points.push_back(
          {0.5f * u(rng) + 0.01f, 0.5f * u(rng) + 0.01f, 0.5f * (u(rng) % 2) + 0.01f});
  }
  struct Case {
    double hit, miss, clamp_min, clamp_max;
  };
  for (const Case c : {Case{0.8, 0.3, 0.2, 0.9}, Case{0.6, 0.45, 0.3, 0.8}}) {
    CAPTURE(c.hit);
    knnocc::MapperOptions options;
    options.occupancy.clamp_min = knnocc::logodds(c.clamp_min);
    options.occupancy.clamp_max = knnocc::logodds(c.clamp_max);
    knnocc::Mapper<knnocc::OctoMapModel> mapper(
        0.1, knnocc::OctoMapModel::from_probabilities(c.hit, c.miss), options);
    octomap::OcTree tree(0.1);
    tree.setProbHit(c.hit);
    tree.setProbMiss(c.miss);
    tree.setClampingThresMin(c.clamp_min);
    tree.setClampingThresMax(c.clamp_max);
    for (const auto& s : scans) mapper.insert_keyframe(s.origin, s.points, {});
    octomap_insert(tree, scans);
    expect_same_map(mapper.map(), tree);
    std::size_t at_min = 0, at_max = 0;
    mapper.map().for_each_voxel([&](const OcKey&, float v) {
      at_min += v == options.occupancy.clamp_min;
      at_max += v == options.occupancy.clamp_max;
    });
    CHECK(at_min > 100);
    CHECK(at_max > 10);
  }
}

TEST_CASE("octomap_reference.ray_keys_and_cast_ray") {
  knnocc::test::Rng rng(99);
  std::uniform_real_distribution<float> u(-20.f, 20.f);
  octomap::OcTree tree(0.1);
  OccupancyMap<OcKey> map(0.1);
  octomap::KeyRay theirs;
  std::vector<OcKey> ours;
  std::size_t keys = 0, differing = 0;
  for (int i = 0; i < 20000; ++i) {
    Point3f o{u(rng), u(rng), u(rng)}, e{u(rng), u(rng), u(rng)};
    if (i % 3 == 0) e.z = o.z;  // planar rays: step 0 on one axis
    const bool a = tree.computeRayKeys(octomap::point3d(o.x, o.y, o.z),
                                       octomap::point3d(e.x, e.y, e.z), theirs);
    const bool b = knnocc::compute_ray_keys(map.grid(), o, e, ours);
    REQUIRE(a == b);
    keys += ours.size();
    bool same = theirs.size() == ours.size();
    std::size_t j = 0;
    for (auto it = theirs.begin(); same && it != theirs.end(); ++it, ++j)
      same = (*it)[0] == ours[j][0] && (*it)[1] == ours[j][1] && (*it)[2] == ours[j][2];
    differing += !same;
  }
  MESSAGE(keys << " ray keys compared over 20000 rays");
  CHECK(differing == 0);

  // castRay on a real map: same status and same end voxel.
  std::vector<Scan> scans(1);
  std::uniform_real_distribution<float> w(-4.f, 4.f);
  for (int i = 0; i < 5000; ++i) scans[0].points.push_back({w(rng), w(rng), w(rng)});
  insert_all(map, scans);
  octomap_insert(tree, scans);
  std::uniform_real_distribution<float> dir(-1.f, 1.f);
  std::size_t hits = 0;
  for (int i = 0; i < 5000; ++i) {
    const Point3f o{w(rng) * 0.1f, w(rng) * 0.1f, w(rng) * 0.1f}, d{dir(rng), dir(rng), dir(rng)};
    for (const bool ignore_unknown : {false, true}) {
      const double max_range = (i % 2) ? 3.0 : -1.0;
      octomap::point3d end;
      const bool a = tree.castRay(octomap::point3d(o.x, o.y, o.z), octomap::point3d(d.x, d.y, d.z),
                                  end, ignore_unknown, max_range);
      const auto r = knnocc::cast_ray(map, o, d, ignore_unknown, max_range);
      REQUIRE(a == r.hit());
      hits += a;
      CHECK(end.x() == r.end.x);
      CHECK(end.y() == r.end.y);
      CHECK(end.z() == r.end.z);
    }
  }
  MESSAGE(hits << " castRay hits agree");
}
#endif
