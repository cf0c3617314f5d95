// Change sets (knn/change_set.hpp): explicit lists, diff_by_id, SpatialChangeDetector,
// KeyframeUnion.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <unordered_map>
#include <vector>

#include <knnocc/knn/tracker.hpp>

#include "knn_oracle.hpp"
#include "test_support.hpp"

using knnocc::ChangeSet;
using knnocc::Point3d;
using knnocc::test::brute_force;
using knnocc::test::Cloud;
using knnocc::test::expect_matches;
using knnocc::test::Truth;

TEST_CASE("knn_tracker.change_set_builders") {
  std::unordered_map<std::uint64_t, Point3d> a{{1, {0, 0, 0}}, {2, {1, 0, 0}}, {3, {2, 0, 0}}};
  std::unordered_map<std::uint64_t, Point3d> b{{2, {1, 0, 0}}, {3, {2, 0.5, 0}}, {4, {5, 0, 0}}};
  const ChangeSet cs = knnocc::diff_by_id(a, b);
  REQUIRE(cs.added.size() == 1);
  CHECK(cs.added[0].id == 4);
  CHECK(cs.removed == std::vector<std::uint64_t>{1});
  REQUIRE(cs.moved.size() == 1);
  CHECK(cs.moved[0].id == 3);
  CHECK(knnocc::diff_by_id(a, b, 1.0).moved.empty());  // within tolerance

  knnocc::SpatialChangeDetector det(0.5);
  const std::vector<Point3d> c1 = {{0.1, 0.1, 0.1}, {0.2, 0.1, 0.1}, {3, 3, 3}};
  const ChangeSet first = det.update(c1);
  CHECK(first.added.size() == 3);
  CHECK(first.removed.empty());
  // Voxel of (3,3,3) empties; a new voxel appears; the first voxel stays with its old points.
  const std::vector<Point3d> c2 = {{0.15, 0.1, 0.1}, {7, 0, 0}, {7.1, 0, 0}};
  const ChangeSet second = det.update(c2);
  REQUIRE(second.added.size() == 2);
  CHECK(second.added[0].id == 3);
  CHECK(second.added[0].p.x == 7.0);
  CHECK(second.removed == std::vector<std::uint64_t>{2});
  // Keyframe union: an id joins once at its first position; without ids every point is new.
  knnocc::KeyframeUnion with_ids, without_ids;
  const std::vector<Point3d> kf = {{0, 0, 0}, {1, 0, 0}};
  CHECK(with_ids.add(kf, {7, 8}).added.size() == 2);
  const ChangeSet again = with_ids.add({{5, 5, 5}, {2, 0, 0}}, {7, 9});
  REQUIRE(again.added.size() == 1);
  CHECK(again.added[0].id == 9);
  CHECK(without_ids.add(kf, {}).added.size() == 2);
  const ChangeSet fresh = without_ids.add(kf, {});
  REQUIRE(fresh.added.size() == 2);
  CHECK(fresh.added[0].id == 2);
  // Non-finite entries count as absent, so an id that gets a position later is an addition.
  const Point3d nan_p{std::nan(""), 0, 0};
  CHECK(knnocc::diff_by_id({}, {{7, nan_p}}).empty());
  const ChangeSet later = knnocc::diff_by_id({{7, nan_p}}, {{7, {1, 2, 3}}});
  REQUIRE(later.added.size() == 1);
  CHECK(later.added[0].id == 7);
  CHECK(knnocc::diff_by_id({{7, {1, 2, 3}}}, {{7, nan_p}}).removed ==
        std::vector<std::uint64_t>{7});
  knnocc::KeyframeUnion nan_first;
  CHECK(nan_first.add({nan_p}, {4}).added.empty());
  CHECK(nan_first.add({{1, 1, 1}}, {4}).added.size() == 1);  // joins at its first finite sighting
  CHECK(nan_first.skipped_nonfinite() == 1);
  CHECK_THROWS_AS(nan_first.add({{2, 2, 2}}, {}), std::invalid_argument);  // ids, then none
  // Feeding the tracker the detector's changes keeps a consistent cloud.
  knnocc::TrackerParams params;
  params.k = 1;
  knnocc::KnnTracker<> tr(params);
  tr.apply(first);
  tr.apply(second);
  CHECK(tr.size() == 4);
  CHECK(tr.s(3) == doctest::Approx(0.1));
}
