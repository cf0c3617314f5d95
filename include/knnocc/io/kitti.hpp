// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// KITTI odometry data: velodyne scans (.bin: float32 x y z reflectance per point, little-endian,
// sensor frame) and the Velodyne-to-camera transform "Tr" of calib.txt. The poses files
// (3x4 matrices) are read by read_kitti_poses() in trajectory.hpp.
//
// KITTI's poses are those of the left camera, so a scan goes to the world frame with
// pose_i * Tr (see Sequence: a folder with velodyne/, poses.txt and calib.txt does this).

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "atomic_file.hpp"
#include "cloud.hpp"
#include "detail/bytes.hpp"
#include "detail/file_text.hpp"
#include "error.hpp"
#include "trajectory.hpp"

namespace knnocc::io {

/// The points of a velodyne .bin scan (reflectance dropped). A size that is not a multiple of
/// 16 bytes is an io::Error (a truncated or foreign file).
inline Cloud read_kitti_bin(const std::string& path) {
  const detail::FileBuffer buf = detail::read_file(path);
  if (buf.size() % 16 != 0) {
    throw Error(path, "size " + std::to_string(buf.size()) +
                          " bytes is not a multiple of 16 (KITTI .bin: float32 x y z reflectance "
                          "per point); truncated or not a KITTI scan");
  }
  const auto* p = reinterpret_cast<const unsigned char*>(buf.data());
  Cloud cloud;
  cloud.points.resize(buf.size() / 16);
  for (std::size_t i = 0; i < cloud.points.size(); ++i, p += 16) {
    cloud.points[i] = Point3f{detail::load_le<float>(p), detail::load_le<float>(p + 4),
                              detail::load_le<float>(p + 8)};
  }
  return cloud;
}

/// Writes a velodyne .bin scan (reflectance 0).
inline void write_kitti_bin(const std::string& path, const std::vector<Point3f>& pts) {
  std::string out(pts.size() * 16, '\0');
  for (std::size_t i = 0; i < pts.size(); ++i) {
    detail::store_le(&out[16 * i], pts[i].x);
    detail::store_le(&out[16 * i + 4], pts[i].y);
    detail::store_le(&out[16 * i + 8], pts[i].z);
  }
  AtomicFile file(path);
  file.write(out);
  file.commit();
}

/// The "Tr:" line of a KITTI odometry calib.txt (Velodyne to left camera, 3x4 row-major).
inline Eigen::Isometry3d read_kitti_calib_tr(const std::string& path) {
  const detail::FileBuffer buf = detail::read_file(path);
  bool found = false;
  Eigen::Isometry3d tr = Eigen::Isometry3d::Identity();
  detail::for_each_line(buf.data(), buf.end(), [&](std::size_t line, const char* b, const char* e) {
    while (b != e && detail::is_blank(*b)) ++b;
    if (e - b < 3 || b[0] != 'T' || b[1] != 'r' || b[2] != ':') return;
    const std::string at = "line " + std::to_string(line) + ": ";
    if (found) throw Error(path, at + "a second Tr: line");
    double v[13];
    const std::size_t n = detail::scan_line_numbers(path, line, b + 3, e, v, 13, true);
    if (n != 12) throw Error(path, at + "Tr: needs 12 numbers, found " + std::to_string(n));
    Pose pose;
    const std::string problem = detail::pose_from_matrix(v, pose);
    if (!problem.empty()) throw Error(path, at + "Tr: " + problem);
    tr = pose.transform();
    found = true;
  });
  if (!found) throw Error(path, "no 'Tr:' line (Velodyne to camera transform)");
  return tr;
}

}  // namespace knnocc::io
