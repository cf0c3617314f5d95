#pragma once
// Sensor poses: the "stamp tx ty tz qx qy qz qw" trajectory format, and moving clouds into the
// world frame with them.
//
// One pose per line (sensor-to-world). NOTE the quaternion order on the line is x y z w, while
// Eigen::Quaterniond's constructor takes w first. '#' starts a comment anywhere on a line; blank
// lines are skipped. Each data line must hold exactly 8 numbers, all finite. A quaternion whose
// norm is off 1 by more than 1e-3 is an error (it usually means a column-order mix-up); smaller
// deviations, e.g. from 4-decimal files, are normalised away.

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "cloud.hpp"
#include "detail/file_text.hpp"
#include "error.hpp"

namespace knnocc::io {

struct Pose {
  double stamp = 0;
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();

  // Sensor-to-world rigid transform.
  Eigen::Isometry3d transform() const {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = q.toRotationMatrix();
    T.translation() = t;
    return T;
  }
};

inline std::vector<Pose> read_poses(const std::string& path) {
  const detail::FileBuffer buf = detail::read_file(path);
  std::vector<Pose> poses;
  detail::for_each_line(buf.data(), buf.end(), [&](std::size_t line, const char* b, const char* e) {
    const std::string at = "line " + std::to_string(line) + ": ";
    double v[9];
    // Ask for one more than needed so a line with extra columns is caught.
    const std::size_t n = detail::scan_line_numbers(path, line, b, e, v, 9, true);
    if (n == 0) return;  // blank or comment-only line
    if (n != 8) {
      throw Error(path, at + "expected 8 numbers (stamp tx ty tz qx qy qz qw), found " +
                            (n > 8 ? std::string("more") : std::to_string(n)));
    }
    for (std::size_t k = 0; k < 8; ++k) {
      if (!std::isfinite(v[k])) throw Error(path, at + "non-finite number");
    }
    Pose pose;
    pose.stamp = v[0];
    pose.t = Eigen::Vector3d(v[1], v[2], v[3]);
    pose.q = Eigen::Quaterniond(v[7], v[4], v[5], v[6]);  // (w, x, y, z) from "qx qy qz qw"
    const double norm = pose.q.norm();
    if (!(std::abs(norm - 1.0) <= 1e-3)) {
      char text[32];
      std::snprintf(text, sizeof text, "%g", norm);
      throw Error(path, at + "quaternion norm " + text + " is not 1");
    }
    pose.q.normalize();
    poses.push_back(pose);
  });
  return poses;
}

// out[i] = R * in[i] + t, evaluated in double and rounded to float once at the end, so large
// world offsets do not add float rounding on top of the input's. `out` is resized to in.size()
// and may be the same vector as `in`. Non-finite input points stay non-finite.
inline void transform_to_world(const Pose& pose, const std::vector<Point3f>& in,
                               std::vector<Point3f>& out) {
  const Eigen::Matrix3d R = pose.q.toRotationMatrix();
  const Eigen::Vector3d& t = pose.t;
  out.resize(in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    const Eigen::Vector3d p(in[i].x, in[i].y, in[i].z);
    const Eigen::Vector3d w = R * p + t;
    out[i] = Point3f{detail::to_float(w.x()), detail::to_float(w.y()), detail::to_float(w.z())};
  }
}

}  // namespace knnocc::io
