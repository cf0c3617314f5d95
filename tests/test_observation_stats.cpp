// How map points are observed (eval/observation_stats.hpp): a hand-made sequence with known
// answers, and random ones against an independent computation (Eigen quaternions for the camera
// frames, every keyframe tested for every point).

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include <knnocc/eval/observation_stats.hpp>

using namespace knnocc;

TEST_CASE("observation_stats: views, span and detection of a hand-made sequence") {
  // Three cameras at the origin looking along +z (camera frame = world frame).
  std::vector<eval::ObservedKeyframe> kfs(3);
  kfs[0].points = {{0, 0, 2}, {0.5, 0.2, 3}, {-0.4, -0.3, 1}};
  kfs[0].ids = {1, 2, 3};
  kfs[1].points = {{0.5, 0.2, 3}, {-0.4, -0.3, 1}};
  kfs[1].ids = {2, 3};
  kfs[2].points = {{0, 0, 2}, {0.5, 0.2, 3}, {0.1, 0.1, 5}};
  kfs[2].ids = {1, 2, 4};
  const eval::ViewModel view = eval::estimate_view(kfs, 0.0);  // the extreme angles
  CHECK(view.h_lo == doctest::Approx(std::atan2(-0.4, 1)));
  CHECK(view.h_hi == doctest::Approx(std::atan2(0.5, 3)));
  CHECK(view.v_lo == doctest::Approx(std::atan2(-0.3, 1)));
  CHECK(view.r_lo[1] == doctest::Approx(std::sqrt(0.16 + 0.09 + 1)));
  CHECK(view.r_hi[2] == doctest::Approx(std::sqrt(0.02 + 25)));
  const std::vector<eval::PointObservations> pts = eval::observe_points(kfs, view);
  REQUIRE(pts.size() == 4);
  // id 1: seen by 0 and 2; keyframe 1's range (1.28 .. 3.05 m) holds it too.
  CHECK(pts[0].views == 2);
  CHECK(pts[0].span() == 2);
  CHECK(pts[0].in_view == 3);
  CHECK(pts[0].detection() == doctest::Approx(2.0 / 3));
  CHECK(pts[1].views == 3);
  CHECK(pts[1].detection() == 1.0);
  // id 4 at 5 m: beyond keyframes 0 and 1's farthest points; only its observer counts.
  CHECK(pts[3].views == 1);
  CHECK(pts[3].in_view == 1);
  const eval::ObservationSummary s = eval::summarize(pts);
  CHECK(s.points == 4);
  CHECK(s.multiview == 3);
  CHECK(s.views[0] == 0.25);
  CHECK(s.views[1] == 0.5);
  CHECK(s.views[2] == 0.25);
  CHECK(s.within5 == 1.0);
  CHECK(s.span_median == 2);  // spans 2, 2, 1
}

TEST_CASE("observation_stats: in-view counts match an independent computation") {
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<eval::ObservedKeyframe> kfs(25);
  std::vector<Eigen::Quaterniond> qs;
  std::vector<Eigen::Vector3d> sites(400);
  for (auto& s : sites) s = Eigen::Vector3d(3 * u(rng), 3 * u(rng), 3 * u(rng));
  for (std::size_t i = 0; i < kfs.size(); ++i) {
    const Eigen::Quaterniond q = Eigen::Quaterniond(
        Eigen::AngleAxisd(M_PI * u(rng), Eigen::Vector3d(u(rng), u(rng), 1).normalized()));
    const Eigen::Vector3d o(4 * u(rng), 4 * u(rng), u(rng));
    qs.push_back(q);
    const Eigen::Matrix3d r = q.toRotationMatrix();
    for (int a = 0; a < 9; ++a) kfs[i].rotation[static_cast<std::size_t>(a)] = r(a / 3, a % 3);
    kfs[i].origin = {o.x(), o.y(), o.z()};
    for (std::size_t s = 0; s < sites.size(); ++s) {
      const Eigen::Vector3d c = r.transpose() * (sites[s] - o);
      if (c.z() > 0.2 && std::fabs(c.x() / c.z()) < 0.8 && std::fabs(c.y() / c.z()) < 0.6 &&
          rng() % 3 == 0) {
        kfs[i].points.push_back({sites[s].x(), sites[s].y(), sites[s].z()});
        kfs[i].ids.push_back(s);
      }
    }
  }
  const eval::ViewModel view = eval::estimate_view(kfs);
  const std::vector<eval::PointObservations> pts = eval::observe_points(kfs, view);
  REQUIRE(pts.size() > 100);
  for (const eval::PointObservations& p : pts) {
    const Eigen::Vector3d w = sites[p.id];
    std::uint32_t in = 0, views = 0;
    for (std::size_t i = 0; i < kfs.size(); ++i) {
      const bool observes = std::count(kfs[i].ids.begin(), kfs[i].ids.end(), p.id) > 0;
      views += observes;
      const Eigen::Vector3d o(kfs[i].origin.x, kfs[i].origin.y, kfs[i].origin.z);
      const Eigen::Vector3d c = qs[i].conjugate() * (w - o);
      const double h = std::atan2(c.x(), c.z()), v = std::atan2(c.y(), c.z()), r = c.norm();
      const bool inside = c.z() > 0 && h >= view.h_lo && h <= view.h_hi && v >= view.v_lo &&
                          v <= view.v_hi && r >= view.r_lo[i] && r <= view.r_hi[i];
      in += inside || observes;
    }
    CHECK(p.views == views);
    CHECK(p.in_view == in);
  }
}
