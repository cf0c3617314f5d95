// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Keyframe poses for the live mapper: RigidPose (sensor to world, rotation matrix + translation)
// and pose_traits, the customisation point that moves a sensor-frame point into the world.
//
// LiveMapper<Model, Key, Pose> takes any Pose type that is copyable, equality comparable (a
// re-pose to an equal pose is no change) and has a pose_traits specialisation providing
//   static Point3d origin(const Pose&)                     the sensor position in the world
//   static Point3d to_world(const Pose&, const Point3f&)   a sensor-frame point in the world
// The map equals a from-scratch Mapper fed with exactly these world points, so a caller that
// transforms points its own way (e.g. with Eigen, as the command-line tool does) specialises
// pose_traits for its own pose type rather than converting to RigidPose.

#include <array>
#include <cmath>
#include <type_traits>
#include <utility>

#include "../core/point3.hpp"

namespace knnocc {

/// Sensor-to-world rigid transform: world = R * p + t, R row-major.
struct RigidPose {
  std::array<double, 9> r{1, 0, 0, 0, 1, 0, 0, 0, 1};
  std::array<double, 3> t{0, 0, 0};

  /// A rotation of `angle` radians about the z axis, then the translation (tx, ty, tz).
  static RigidPose yaw(double angle, double tx, double ty, double tz) {
    const double c = std::cos(angle), s = std::sin(angle);
    RigidPose p;
    p.r = {c, -s, 0, s, c, 0, 0, 0, 1};
    p.t = {tx, ty, tz};
    return p;
  }
  bool finite() const {
    for (double v : r)
      if (!std::isfinite(v)) return false;
    for (double v : t)
      if (!std::isfinite(v)) return false;
    return true;
  }
  friend bool operator==(const RigidPose& a, const RigidPose& b) {
    return a.r == b.r && a.t == b.t;
  }
  friend bool operator!=(const RigidPose& a, const RigidPose& b) { return !(a == b); }
};

/// How a pose moves points; specialise for your own pose type (see the top of this file).
template <class Pose>
struct pose_traits;

template <>
struct pose_traits<RigidPose> {
  static Point3d origin(const RigidPose& p) { return {p.t[0], p.t[1], p.t[2]}; }
  static Point3d to_world(const RigidPose& p, const Point3f& q) {
    const double x = q.x, y = q.y, z = q.z;
    return {p.r[0] * x + p.r[1] * y + p.r[2] * z + p.t[0],
            p.r[3] * x + p.r[4] * y + p.r[5] * z + p.t[1],
            p.r[6] * x + p.r[7] * y + p.r[8] * z + p.t[2]};
  }
};

namespace detail {
template <class Pose, class = void>
struct has_pose_traits : std::false_type {};
template <class Pose>
struct has_pose_traits<
    Pose, std::void_t<decltype(pose_traits<Pose>::origin(std::declval<const Pose&>())),
                      decltype(pose_traits<Pose>::to_world(std::declval<const Pose&>(),
                                                           std::declval<const Point3f&>()))>>
    : std::true_type {};
}  // namespace detail

}  // namespace knnocc
