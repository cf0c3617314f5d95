// RigidPose and pose_traits (live/rigid_pose.hpp): the transform, yaw poses, equality.
#include <doctest/doctest.h>

#include <cmath>

#include <knnocc/live/rigid_pose.hpp>

using knnocc::Point3d;
using knnocc::Point3f;
using knnocc::pose_traits;
using knnocc::RigidPose;

TEST_CASE("rigid_pose.moves_points_into_the_world") {
  const RigidPose id;
  const Point3d p = pose_traits<RigidPose>::to_world(id, Point3f{1.5f, -2.0f, 0.25f});
  CHECK(p.x == 1.5);
  CHECK(p.y == -2.0);
  CHECK(p.z == 0.25);
  const RigidPose q = RigidPose::yaw(M_PI / 2, 1.0, 2.0, 3.0);  // x -> y, then shifted
  const Point3d w = pose_traits<RigidPose>::to_world(q, Point3f{1.0f, 0.0f, 0.0f});
  CHECK(w.x == doctest::Approx(1.0));
  CHECK(w.y == doctest::Approx(3.0));
  CHECK(w.z == doctest::Approx(3.0));
  const Point3d o = pose_traits<RigidPose>::origin(q);
  CHECK((o.x == 1.0 && o.y == 2.0 && o.z == 3.0));
}

TEST_CASE("rigid_pose.equality_and_finiteness") {
  const RigidPose a = RigidPose::yaw(0.3, 1, 2, 3), b = RigidPose::yaw(0.3, 1, 2, 3);
  CHECK(a == b);
  RigidPose c = a;
  c.t[2] = std::nextafter(c.t[2], 10.0);  // one ulp is a different pose
  CHECK(a != c);
  CHECK(a.finite());
  c.r[4] = std::nan("");
  CHECK_FALSE(c.finite());
  static_assert(knnocc::detail::has_pose_traits<RigidPose>::value);
  static_assert(!knnocc::detail::has_pose_traits<int>::value);
}
