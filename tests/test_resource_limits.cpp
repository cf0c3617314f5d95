// The tool's foresight of a scan's memory (examples/cli/resource_limits.hpp): the bricks that
// at_least_bricks_by_angle() and at_least_bricks() claim a scan needs are never more than the
// bricks inserting it creates (a claim above the truth would refuse work that fits).

#include <doctest/doctest.h>

#include "test_support.hpp"

#ifdef KNNOCC_TEST_TOOL_HEADERS
#include <cmath>
#include <random>
#include <vector>

#include <knnocc/insertion/scan_inserter.hpp>

#include "resource_limits.hpp"

using namespace knnocc;

namespace {

// A scan from `origin`: rays in `bundles` random directions, `per_bundle` rays each within
// `spread` radians of their bundle's direction (near-parallel rays share bricks), lengths
// between lo and hi.
std::vector<Point3f> scan(const Point3d& origin, int bundles, int per_bundle, double spread,
                          double lo, double hi, unsigned seed) {
  knnocc::test::Rng rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> len(lo, hi);
  std::vector<Point3f> pts;
  for (int b = 0; b < bundles; ++b) {
    double d[3] = {g(rng), g(rng), g(rng)};
    const double n = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (double& c : d) c /= n;
    for (int k = 0; k < per_bundle; ++k) {
      double e[3] = {d[0] + spread * g(rng), d[1] + spread * g(rng), d[2] + spread * g(rng)};
      const double m = std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
      const double l = len(rng);
      pts.push_back(Point3f{static_cast<float>(origin.x + l * e[0] / m),
                            static_cast<float>(origin.y + l * e[1] / m),
                            static_cast<float>(origin.z + l * e[2] / m)});
    }
  }
  return pts;
}

std::size_t bricks_created(const Point3d& origin, const std::vector<Point3f>& pts, double res,
                           double max_range) {
  OccupancyMap<OcKey> map(res);
  ScanInserter<OcKey> inserter(map);
  inserter.insert_point_cloud(Point3f{static_cast<float>(origin.x), static_cast<float>(origin.y),
                                      static_cast<float>(origin.z)},
                              pts, max_range);
  return map.num_bricks();
}

}  // namespace

TEST_CASE("resource_limits.brick bounds never exceed the bricks inserting the scan creates") {
  struct Case {
    int bundles, per_bundle;
    double spread, lo, hi, res, max_range;
  };
  const Case cases[] = {
      {400, 1, 0.0, 0.2, 2.0, 0.002, -1},     // spread-out rays
      {40, 25, 0.002, 0.5, 2.5, 0.002, -1},   // bundles of near-parallel rays
      {40, 25, 0.02, 0.5, 2.5, 0.001, 1.2},   // cut at max_range
      {2000, 1, 0.0, 0.05, 0.3, 0.001, -1},   // short rays: nothing to prove by angle
      {10, 200, 0.0005, 1.0, 3.0, 0.005, -1}  // tight bundles, coarser bricks
  };
  unsigned seed = 1;
  double proved_total = 0;
  for (const Case& c : cases) {
    for (const Point3d origin : {Point3d{0, 0, 0}, Point3d{0.31, -0.17, 0.05}}) {
      CAPTURE(seed);
      const auto pts = scan(origin, c.bundles, c.per_bundle, c.spread, c.lo, c.hi, seed++);
      const std::size_t truth = bricks_created(origin, pts, c.res, c.max_range);
      const double by_angle = cli::at_least_bricks_by_angle(origin, pts, c.res, c.max_range);
      CHECK(by_angle >= 0);
      CHECK(by_angle <= double(truth));
      proved_total += by_angle / double(truth);
      // The sampling bound: counted up to `enough`, never above the truth either.
      const std::size_t sampled =
          cli::at_least_bricks(origin, pts, c.res, c.max_range, true, truth / 4);
      CHECK(sampled <= truth);
    }
  }
  // The bound is not vacuous: on these scans it proves a good share of the bricks.
  CHECK(proved_total / 10 > 0.05);
}

TEST_CASE("resource_limits.the angle bound proves a long fine scan too big without walking it") {
  // 20,000 rays of 2-3 m at 0.1 mm: ~3e8 brick visits, too many to sample.
  const Point3d origin{0, 0, 0};
  const auto pts = scan(origin, 20000, 1, 0.0, 2.0, 3.0, 99);
  const double by_angle = cli::at_least_bricks_by_angle(origin, pts, 1e-4, -1);
  // Each ray holds (l - r0) / (sqrt(3) * 0.8 mm) bricks of its own beyond r0 at some angle.
  CHECK(by_angle > 5e6);
  CHECK(cli::at_least_bricks(origin, pts, 1e-4, -1, true, 5000000) > 5000000);
}
#endif
