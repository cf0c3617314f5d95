// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Sensor poses: the TUM trajectory format "stamp tx ty tz qx qy qz qw", KITTI's 3x4 matrices
// (12 numbers per line, row-major [R | t]), and moving clouds into the world frame with them.
// read_trajectory() tells the two apart by the number of values per line.
//
// One pose per line (sensor-to-world). NOTE the quaternion order on the line is x y z w, while
// Eigen::Quaterniond's constructor takes w first. '#' starts a comment anywhere on a line; blank
// lines are skipped. Each data line must hold exactly 8 numbers, all finite. A quaternion whose
// norm is off 1 by more than 1e-3 is an error (it usually means a column-order mix-up); smaller
// deviations, e.g. from 4-decimal files, are normalised away.
// KITTI lines have no time stamp (stamp = line index); R must be a rotation within 1e-3
// (R^T R = I, det R = +1), else io::Error.

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "atomic_file.hpp"
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

namespace detail {

// A TUM line "stamp tx ty tz qx qy qz qw" into `pose`; false for a blank or comment-only line.
inline bool parse_tum_line(const std::string& path, std::size_t line, const char* b, const char* e,
                           Pose& pose) {
  const std::string at = "line " + std::to_string(line) + ": ";
  double v[9];
  // Ask for one more than needed so a line with extra columns is caught.
  const std::size_t n = scan_line_numbers(path, line, b, e, v, 9, true);
  if (n == 0) return false;
  if (n != 8) {
    throw Error(path, at + "expected 8 numbers (stamp tx ty tz qx qy qz qw), found " +
                          (n > 8 ? std::string("more") : std::to_string(n)));
  }
  for (std::size_t k = 0; k < 8; ++k) {
    if (!std::isfinite(v[k])) throw Error(path, at + "non-finite number");
  }
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
  return true;
}

// A pose from a row-major 3x4 [R | t]; "" on success, else the problem.
inline std::string pose_from_matrix(const double m[12], Pose& pose) {
  for (int k = 0; k < 12; ++k) {
    if (!std::isfinite(m[k])) return "non-finite number";
  }
  Eigen::Matrix3d R;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) R(r, c) = m[4 * r + c];
  }
  const double off = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (!(off <= 1e-3) || !(R.determinant() > 0.0)) {
    char text[64];
    std::snprintf(text, sizeof text, "%g", off);
    return std::string("the 3x3 part is not a rotation (|R^T R - I| = ") + text +
           ", det = " + std::to_string(R.determinant()) + ")";
  }
  pose.q = Eigen::Quaterniond(R).normalized();
  pose.t = Eigen::Vector3d(m[3], m[7], m[11]);
  return {};
}

// A KITTI line (12 numbers, [R | t] row by row) into `pose`, whose stamp becomes `index`; false
// for a blank or comment-only line.
inline bool parse_kitti_line(const std::string& path, std::size_t line, const char* b,
                             const char* e, std::size_t index, Pose& pose) {
  const std::string at = "line " + std::to_string(line) + ": ";
  double v[13];
  const std::size_t n = scan_line_numbers(path, line, b, e, v, 13, true);
  if (n == 0) return false;
  if (n != 12) {
    throw Error(path, at + "expected 12 numbers (a 3x4 pose matrix, row by row), found " +
                          (n > 12 ? std::string("more") : std::to_string(n)));
  }
  const std::string problem = pose_from_matrix(v, pose);
  if (!problem.empty()) throw Error(path, at + problem);
  pose.stamp = static_cast<double>(index);
  return true;
}

inline void append_number(std::string& out, double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", v);  // reads back to the same double
  out += text;
}

}  // namespace detail

inline std::vector<Pose> read_poses(const std::string& path) {
  const detail::FileBuffer buf = detail::read_file(path);
  std::vector<Pose> poses;
  detail::for_each_line(buf.data(), buf.end(), [&](std::size_t line, const char* b, const char* e) {
    Pose pose;
    if (detail::parse_tum_line(path, line, b, e, pose)) poses.push_back(pose);
  });
  return poses;
}

// KITTI odometry poses: one "r11 r12 r13 tx r21 r22 r23 ty r31 r32 r33 tz" line per scan.
inline std::vector<Pose> read_kitti_poses(const std::string& path) {
  const detail::FileBuffer buf = detail::read_file(path);
  std::vector<Pose> poses;
  detail::for_each_line(buf.data(), buf.end(), [&](std::size_t line, const char* b, const char* e) {
    Pose pose;
    if (detail::parse_kitti_line(path, line, b, e, poses.size(), pose)) poses.push_back(pose);
  });
  return poses;
}

// TUM (8 values per line) or KITTI (12 values per line), decided by the first data line. The
// file is read piece by piece: a data line after `max_poses` poses is an io::Error naming it, and
// the rest of the file is not read (a huge file where a few poses belong costs nothing). `lines`,
// when given, gets each pose's line number.
inline std::vector<Pose> read_trajectory(const std::string& path,
                                         std::size_t max_poses = static_cast<std::size_t>(-1),
                                         std::vector<std::size_t>* lines = nullptr) {
  std::vector<Pose> poses;
  std::size_t values = 0;  // 12: KITTI, else TUM; 0 until the first data line
  if (lines) lines->clear();
  detail::for_each_file_line(path, [&](std::size_t line, const char* b, const char* e) {
    if (values == 0) {
      double v[13];
      values = detail::scan_line_numbers(path, line, b, e, v, 13, true);
      if (values == 0) return;
    }
    Pose pose;
    const bool data = values == 12 ? detail::parse_kitti_line(path, line, b, e, poses.size(), pose)
                                   : detail::parse_tum_line(path, line, b, e, pose);
    if (!data) return;
    if (poses.size() == max_poses)
      throw Error(path, "line " + std::to_string(line) + ": more poses than the " +
                            std::to_string(max_poses) + " expected");
    poses.push_back(pose);
    if (lines) lines->push_back(line);
  });
  return poses;
}

inline void write_tum_poses(const std::string& path, const std::vector<Pose>& poses) {
  std::string out = "# stamp tx ty tz qx qy qz qw\n";
  for (const Pose& p : poses) {
    const double v[8] = {p.stamp, p.t.x(), p.t.y(), p.t.z(), p.q.x(), p.q.y(), p.q.z(), p.q.w()};
    for (int i = 0; i < 8; ++i) {
      if (i) out += ' ';
      detail::append_number(out, v[i]);
    }
    out += '\n';
  }
  AtomicFile file(path);
  file.write(out);
  file.commit();
}

inline void write_kitti_poses(const std::string& path, const std::vector<Pose>& poses) {
  std::string out;
  for (const Pose& p : poses) {
    const Eigen::Matrix3d R = p.q.toRotationMatrix();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) {
        if (r || c) out += ' ';
        detail::append_number(out, c < 3 ? R(r, c) : p.t[r]);
      }
    }
    out += '\n';
  }
  AtomicFile file(path);
  file.write(out);
  file.commit();
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

// The inverse: points in the world frame to the sensor frame, in place, p = R^T (w - t) in
// double. For clouds stored in world coordinates (`knnocc map --points-frame world`).
inline void transform_to_sensor(const Pose& pose, std::vector<Point3f>& points) {
  const Eigen::Matrix3d Rt = pose.q.toRotationMatrix().transpose();
  for (Point3f& p : points) {
    const Eigen::Vector3d s = Rt * (Eigen::Vector3d(p.x, p.y, p.z) - pose.t);
    p = Point3f{detail::to_float(s.x()), detail::to_float(s.y()), detail::to_float(s.z())};
  }
}

}  // namespace knnocc::io
