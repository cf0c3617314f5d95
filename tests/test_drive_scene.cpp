// SPDX-License-Identifier: BSD-3-Clause
// The simulated LiDAR drive (sim/drive_scene.hpp, street_network.hpp, street_objects.hpp,
// plane_noise.hpp): deterministic per seed, a default route long enough to leave OctoMap's key
// range (computed without casting), beams cast to the true first surface, and its noise and
// dropouts measured on the real scan it was calibrated on.

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <set>
#include <utility>
#include <vector>

#include <knnocc/sim/drive_scene.hpp>
#include <knnocc/sim/plane_noise.hpp>

#include "test_support.hpp"

using namespace knnocc;

// Helpers and cases in their own namespace: the suite compiles test files in unity batches.
namespace drive_scene_test {

// A small drive: few scans, a coarse revolution.
sim::DriveSceneParams small(std::size_t scans = 12, int columns = 360) {
  sim::DriveSceneParams p;
  p.scans = scans;
  p.columns = columns;
  return p;
}

bool same_points(const std::vector<Point3f>& a, const std::vector<Point3f>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (a[i].x != b[i].x || a[i].y != b[i].y || a[i].z != b[i].z) return false;
  return true;
}

Eigen::Vector3d to_world(const io::Pose& pose, const Point3f& p) {
  return pose.q * Eigen::Vector3d(p.x, p.y, p.z) + pose.t;
}

// The first surface along o + t d by testing every object (no grid), moving cars at `stamp`.
double brute_force_hit(const sim::DriveScene& scene, const Eigen::Vector3d& o,
                       const Eigen::Vector3d& d, double stamp) {
  double best = d.z() < 0 ? -o.z() / d.z() : HUGE_VAL;
  const Eigen::Vector3d inv = d.cwiseInverse();
  for (const sim::Shape& s : scene.objects().shapes())
    best = std::min(best, sim::ray_entry(s, o, d, inv));
  for (const sim::MovingCar& m : scene.objects().moving_cars())
    best = std::min(best, sim::ray_entry(m.at(stamp), o, d, inv));
  return best;
}

// scan.dat's missing returns: its scan lines (split where consecutive points are more than 20
// degrees apart as seen from the sensor) hold 180 or 181 points in a pattern that repeats every
// 8 lines; the most common count of each of the 8 phases is its full line. Returns the points
// missing from full lines and sets `expected` to the points full lines would hold.
std::size_t missing_returns(const std::vector<Point3f>& pts, std::size_t& expected) {
  std::vector<std::size_t> lines(1, 0);
  for (std::size_t i = 1; i < pts.size(); ++i) {
    const Eigen::Vector3d a(pts[i - 1].x, pts[i - 1].y, pts[i - 1].z),
        b(pts[i].x, pts[i].y, pts[i].z);
    if (a.normalized().dot(b.normalized()) < std::cos(20.0 * M_PI / 180.0)) lines.push_back(0);
    ++lines.back();
  }
  ++lines.front();
  std::size_t missing = 0;
  expected = 0;
  for (std::size_t phase = 0; phase < 8; ++phase) {
    std::vector<std::size_t> counts;
    for (std::size_t l = phase; l < lines.size(); l += 8) counts.push_back(lines[l]);
    std::size_t full = 0, votes = 0;  // the most common count
    for (std::size_t c : std::set<std::size_t>(counts.begin(), counts.end())) {
      const auto n = static_cast<std::size_t>(std::count(counts.begin(), counts.end(), c));
      if (n > votes) full = c, votes = n;
    }
    for (std::size_t c : counts) {
      expected += full;
      missing += c < full ? full - c : 0;
    }
  }
  return missing;
}

// A second noise estimator: each point's distance from the chord of its two neighbours in the
// scan's order (a scan line), along its beam, where the three are one degree step apart or so;
// the robust sd (1.4826 times the median absolute value) divided by sqrt(1.5), the sd of a point's
// error minus the mean of its neighbours'. Per range bin [lo, hi).
double chord_noise(const std::vector<Point3f>& pts, double lo, double hi) {
  std::vector<double> d;
  for (std::size_t i = 1; i + 1 < pts.size(); ++i) {
    const Eigen::Vector3d a(pts[i - 1].x, pts[i - 1].y, pts[i - 1].z),
        b(pts[i].x, pts[i].y, pts[i].z), c(pts[i + 1].x, pts[i + 1].y, pts[i + 1].z);
    if (!(b.norm() >= lo && b.norm() < hi)) continue;
    const double step_a = std::acos(std::min(1.0, a.normalized().dot(b.normalized())));
    const double step_c = std::acos(std::min(1.0, c.normalized().dot(b.normalized())));
    if (std::max(step_a, step_c) > 3 * M_PI / 180 ||
        std::max(step_a, step_c) > 1.5 * std::min(step_a, step_c))
      continue;
    const Eigen::Vector3d chord = (c - a).normalized();
    const double sin = b.normalized().cross(chord).norm();  // the beam against the chord
    if (sin < 0.5) continue;
    const Eigen::Vector3d off = (b - a) - chord * (b - a).dot(chord);
    d.push_back(off.norm() / sin);
  }
  if (d.empty()) return 0;
  std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
  return 1.4826 * d[d.size() / 2] / std::sqrt(1.5);
}

TEST_CASE("drive scene: a seed gives the same drive, a shorter drive is the start of a longer") {
  const sim::DriveScene a(small(6)), b(small(6)), longer(small(40));
  sim::DriveSceneParams other = small(6);
  other.seed = 2;
  const sim::DriveScene c(other);
  bool differs = false;
  for (std::size_t i = 0; i < 6; ++i) {
    const sim::DriveScan sa = a.scan(i), sb = b.scan(i), sl = longer.scan(i);
    CHECK(same_points(sa.cloud.points, sb.cloud.points));
    CHECK(same_points(sa.cloud.points, sl.cloud.points));
    CHECK(sa.labels == sl.labels);
    CHECK(sa.pose.t == sl.pose.t);
    CHECK(sa.pose.q.coeffs() == sl.pose.q.coeffs());
    differs = differs || !same_points(sa.cloud.points, c.scan(i).cloud.points);
  }
  CHECK(differs);
  CHECK(a.scan(3).cloud.points.size() == a.scan(3).cloud.points.size());  // scan() is pure
}

TEST_CASE("drive scene: the default route is 8 km long and leaves OctoMap's key range") {
  // Only the route: no object is made, no beam cast.
  for (std::uint64_t seed : {1, 2, 3, 4, 5}) {
    sim::DriveSceneParams p;
    p.seed = seed;
    const std::vector<io::Pose> poses = sim::drive_poses(p);
    REQUIRE(poses.size() == p.scans);
    CHECK(p.scans >= 2000);
    CHECK(p.route_length() >= 8000);
    double driven = 0, farthest = 0;
    Eigen::Vector3d lo = poses[0].t, hi = lo;
    for (std::size_t i = 0; i < poses.size(); ++i) {
      const io::Pose& q = poses[i];
      CHECK(q.t.z() == doctest::Approx(1.73));
      CHECK(std::fabs(q.q.norm() - 1.0) < 1e-12);
      CHECK(q.stamp == doctest::Approx(double(i) * p.spacing / p.speed));
      const Eigen::Vector3d forward = q.q * Eigen::Vector3d::UnitX();
      if (i > 0) {
        const Eigen::Vector3d step = q.t - poses[i - 1].t;
        driven += step.norm();
        CHECK(step.norm() <= p.spacing + 1e-9);  // a chord of the arc length
        CHECK(step.norm() >= 0.99 * p.spacing);
        CHECK(step.normalized().dot(forward) > 0.9);  // the sensor looks where it drives
      }
      CHECK(std::fabs(forward.z()) < 0.01);  // the body rolls and pitches a little
      farthest = std::max({farthest, std::fabs(q.t.x()), std::fabs(q.t.y())});
      lo = lo.cwiseMin(q.t);
      hi = hi.cwiseMax(q.t);
    }
    CHECK(poses[0].t.head<2>().norm() < 1e-9);  // the start is the world's origin
    CHECK(driven >= 8000);
    CHECK(farthest > 3500);  // beyond +-3276.8 m, OctoMap's 16-bit keys at 0.1 m
    CHECK(lo.x() > -1e-9);   // it never goes west of its start
    CHECK(hi.y() - lo.y() < 2000);
  }
}

TEST_CASE("drive scene: the LiDAR's beams and the first surface they meet") {
  const std::vector<double> e = sim::lidar_elevations(64);
  REQUIRE(e.size() == 64);
  CHECK(e.front() * 180 / M_PI == doctest::Approx(2.0));
  CHECK(e[31] * 180 / M_PI == doctest::Approx(-8.33));
  CHECK(e[32] * 180 / M_PI == doctest::Approx(-8.83));
  CHECK(e.back() * 180 / M_PI == doctest::Approx(-24.8));
  CHECK(std::is_sorted(e.rbegin(), e.rend()));

  sim::DriveSceneParams p = small(10);
  p.range_noise = 0;
  p.dropout = 0;
  const sim::DriveScene scene(p);
  std::set<sim::Surface> seen;
  std::size_t ground = 0, points = 0, compared = 0;
  std::size_t out_of_range = 0, off_ground = 0, below_ground = 0, inside = 0, wrong_hit = 0;
  for (std::size_t i = 0; i < p.scans; ++i) {
    const sim::DriveScan s = scene.scan(i);
    CHECK(s.beams == std::size_t(64) * 360);
    CHECK(s.cloud.points.size() + s.no_return + s.dropped == s.beams);
    CHECK(s.dropped == 0);
    REQUIRE(s.labels.size() == s.cloud.points.size());
    points += s.cloud.points.size();
    const Eigen::Matrix3d R = s.pose.q.toRotationMatrix();
    const sim::ShapeGrid& grid = scene.objects().grid();
    for (std::size_t k = 0; k < s.cloud.points.size(); ++k) {
      const Point3f& q = s.cloud.points[k];
      const double r = Eigen::Vector3d(q.x, q.y, q.z).norm();
      out_of_range += r > p.max_range + 1e-4 || r < p.min_range - 1e-4;
      const Eigen::Vector3d w = to_world(s.pose, q);
      seen.insert(s.labels[k]);
      if (s.labels[k] == sim::Surface::ground) {
        ++ground;
        off_ground += std::fabs(w.z()) > 1e-4;
      } else {
        below_ground += w.z() < -1e-4;
      }
      // No object listed by the grid where the point is has it inside.
      const auto cx = sim::ShapeGrid::cell(w.x()), cy = sim::ShapeGrid::cell(w.y());
      for (auto it = grid.begin(cx, cy); it != grid.end(cx, cy); ++it)
        inside += sim::contains(scene.objects().shapes()[*it], w, 1e-4);
      if (k % 97 == 0) {  // the grid's walk finds the surface that testing every object finds
        const Eigen::Vector3d d = R * (Eigen::Vector3d(q.x, q.y, q.z) / r);
        wrong_hit += std::fabs(brute_force_hit(scene, s.pose.t, d, s.pose.stamp) - r) > 1e-4;
        ++compared;
      }
    }
  }
  CHECK(out_of_range == 0);
  CHECK(off_ground == 0);
  CHECK(below_ground == 0);
  CHECK(inside == 0);
  CHECK(wrong_hit == 0);
  CHECK(compared > 1000);
  CHECK(ground > points / 4);
  for (sim::Surface k :
       {sim::Surface::ground, sim::Surface::building, sim::Surface::trunk, sim::Surface::crown,
        sim::Surface::pole, sim::Surface::parked_car, sim::Surface::moving_car})
    CHECK(seen.count(k) == 1);
}

TEST_CASE("drive scene: shapes, cars and the grid") {
  const Eigen::Vector3d o(0, 0, 1), d = Eigen::Vector3d(1, 0.2, -0.05).normalized();
  const Eigen::Vector3d inv = d.cwiseInverse();
  const sim::Shape box{{5, -5, 0}, {6, 5, 3}, sim::ShapeType::box, sim::Surface::building};
  const sim::Shape cylinder{
      {5, 0.5, 0}, {6, 1.5, 3}, sim::ShapeType::cylinder, sim::Surface::trunk};
  const sim::Shape ellipsoid{{4, -1, 0}, {8, 3, 2}, sim::ShapeType::ellipsoid, sim::Surface::crown};
  for (const sim::Shape& s : {box, cylinder, ellipsoid}) {
    // The entry equals the first of 1e5 samples along the ray that is inside.
    const double t = sim::ray_entry(s, o, d, inv);
    double sampled = HUGE_VAL;
    for (int k = 0; k < 100000 && sampled == HUGE_VAL; ++k)
      if (sim::contains(s, o + d * (k * 1e-4), 0)) sampled = k * 1e-4;
    CHECK(t == doctest::Approx(sampled).epsilon(2e-4));
    CHECK(sim::contains(s, o + d * (t + 1e-3)));
    CHECK_FALSE(sim::contains(s, o + d * (t - 1e-3)));
  }
  CHECK(sim::ray_entry(box, Eigen::Vector3d(5.5, 0, 1), d, inv) == 0);  // from inside
  CHECK(sim::ray_entry(box, o, -d, (-d).cwiseInverse()) == HUGE_VAL);   // behind

  // A moving car stays in its lane and moves.
  sim::MovingCar m;
  m.start = {10, 3};
  m.span = 50;
  m.speed = 8;
  const sim::Shape at0 = m.at(0), at1 = m.at(1);
  CHECK(at0.lo.x() >= 10 - 1e-9);
  CHECK(at0.hi.x() <= 60 + 1e-9);
  CHECK(at1.lo.x() == doctest::Approx(at0.lo.x() + 8 * (50 - 4.5) / 50));
  CHECK(at0.hi.y() - at0.lo.y() == doctest::Approx(1.8));
  for (double t = 0; t < 30; t += 0.7) {
    const sim::Shape s = m.at(t);
    CHECK(s.lo.x() >= 10 - 1e-9);
    CHECK(s.hi.x() <= 60 + 1e-9);
  }

  // The grid lists each shape in every cell its box overlaps.
  const std::vector<sim::Shape> shapes = {box, cylinder, ellipsoid};
  const sim::ShapeGrid grid(shapes);
  for (std::size_t k = 0; k < shapes.size(); ++k)
    for (double x = shapes[k].lo.x(); x <= shapes[k].hi.x(); x += 0.5)
      for (double y = shapes[k].lo.y(); y <= shapes[k].hi.y(); y += 0.5) {
        const auto cx = sim::ShapeGrid::cell(x), cy = sim::ShapeGrid::cell(y);
        CHECK(std::count(grid.begin(cx, cy), grid.end(cx, cy), std::uint32_t(k)) == 1);
      }
  CHECK(grid.begin(100, 100) == nullptr);
}

TEST_CASE("drive scene: noise and dropouts as calibrated, points within range and out of walls") {
  const sim::DriveScene scene(small(3, 1800));
  std::vector<sim::PatchNoise> patches;
  std::size_t returns = 0, dropped = 0, far = 0, inside = 0;
  for (std::size_t i = 0; i < 3; ++i) {
    const sim::DriveScan s = scene.scan(i);
    sim::add_patch_noise(s.cloud.points, patches);
    returns += s.cloud.points.size() + s.dropped;
    dropped += s.dropped;
    for (std::size_t k = 0; k < s.cloud.points.size(); k += 7) {
      const Point3f& q = s.cloud.points[k];
      far += Eigen::Vector3d(q.x, q.y, q.z).norm() > 80.0;
      const Eigen::Vector3d w = to_world(s.pose, q);
      for (const sim::Shape& b : scene.objects().shapes())
        inside += b.surface == sim::Surface::building && sim::contains(b, w, 0.05);
    }
  }
  CHECK(far == 0);
  CHECK(inside == 0);  // by more than 8 sd of the noise
  const sim::PlaneNoise noise = sim::summarize_patch_noise(patches);
  MESSAGE("simulated: median plane-fit noise " << noise.median * 1000 << " mm over "
                                               << noise.patches << " patches, dropped " << dropped
                                               << " of " << returns << " returns");
  CHECK(noise.patches > 1000);
  CHECK(noise.median == doctest::Approx(sim::kCalibratedRangeNoise).epsilon(0.15));
  // Binomial: 3 scans of ~110,000 returns, about 1,100 dropped, sd 33.
  CHECK(double(dropped) / double(returns) ==
        doctest::Approx(sim::kCalibratedDropout).epsilon(0.15));

  // Without noise the statistic sees next to nothing: it measures noise, not the scene.
  sim::DriveSceneParams exact = small(1, 1800);
  exact.range_noise = 0;
  const sim::PlaneNoise none = sim::plane_fit_noise(sim::DriveScene(exact).scan(0).cloud.points);
  CHECK(none.median < 0.2 * sim::kCalibratedRangeNoise);
}

TEST_CASE("drive scene: calibration on the real scan (scan.dat)") {
  const std::vector<Point3f> pts = test::scan_dat_points_or_skip();
  if (pts.empty()) return;
  const sim::PlaneNoise noise = sim::plane_fit_noise(pts);
  for (const sim::PlaneNoiseBin& b : noise.bins)
    MESSAGE("scan.dat plane-fit noise, ranges [" << b.lo << ", " << b.hi << ") m: " << b.patches
                                                 << " patches, median " << b.median * 1000
                                                 << " mm");
  MESSAGE("scan.dat plane-fit noise: " << noise.patches << " patches, median "
                                       << noise.median * 1000 << " mm");
  for (double fraction : {0.01, 0.02, 0.03, 0.05}) {  // larger patches: the walls' own shape
    sim::PlaneNoiseParams p;
    p.radius_fraction = fraction;
    MESSAGE("scan.dat plane-fit noise, patches of radius "
            << fraction * 100 << " % of the range: " << sim::plane_fit_noise(pts, p).median * 1000
            << " mm");
  }
  for (const auto& [lo, hi] : {std::pair(0.5, 2.0), std::pair(2.0, 4.0), std::pair(4.0, 8.0)})
    MESSAGE("scan.dat chord noise, ranges ["
            << lo << ", " << hi << ") m: " << chord_noise(pts, lo, hi) * 1000 << " mm");
  std::size_t expected = 0;
  const std::size_t missing = missing_returns(pts, expected);
  MESSAGE("scan.dat missing returns: " << missing << " of " << expected << " ("
                                       << 100.0 * double(missing) / double(expected) << " %)");
  // The constants of sim/drive_scene.hpp are these measurements.
  CHECK(noise.median == doctest::Approx(sim::kCalibratedRangeNoise).epsilon(0.02));
  CHECK(double(missing) / double(expected) ==
        doctest::Approx(sim::kCalibratedDropout).epsilon(0.02));
  CHECK(expected == 88503);
  // The two noise estimators agree.
  CHECK(chord_noise(pts, 0.5, 8.0) == doctest::Approx(noise.median).epsilon(0.3));
}

}  // namespace drive_scene_test
