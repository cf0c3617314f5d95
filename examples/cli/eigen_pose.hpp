#pragma once
// EigenPose: a sensor-to-world pose applied as the tool's from-scratch path applies it
// (io::transform_to_world, io::keyframe_to_world): R * p + t with Eigen, R from the quaternion
// once. The live mapper (pose_traits) and the Python module move points with it, so their maps
// equal the tool's bit for bit.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <knnocc/core/point3.hpp>
#include <knnocc/io/trajectory.hpp>
#include <knnocc/live/rigid_pose.hpp>

namespace knnocc::cli {

struct EigenPose {
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();

  static EigenPose from(const io::Pose& p) { return {p.q.toRotationMatrix(), p.t}; }
  /// R * (x, y, z) + t in double: io::keyframe_to_world's arithmetic.
  Eigen::Vector3d apply(double x, double y, double z) const {
    return r * Eigen::Vector3d(x, y, z) + t;
  }
  friend bool operator==(const EigenPose& a, const EigenPose& b) {
    return a.r == b.r && a.t == b.t;
  }
};

}  // namespace knnocc::cli

template <>
struct knnocc::pose_traits<knnocc::cli::EigenPose> {
  static Point3d origin(const cli::EigenPose& p) { return {p.t.x(), p.t.y(), p.t.z()}; }
  static Point3d to_world(const cli::EigenPose& p, const Point3f& q) {
    const Eigen::Vector3d w = p.apply(q.x, q.y, q.z);
    return {w.x(), w.y(), w.z()};
  }
};
