// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A sequence folder: poses.txt (one sensor-to-world pose per line, TUM or KITTI format) plus a
// cloud folder, where the i-th cloud in name order belongs to the i-th pose line:
//   clouds/NNNNNN.{ply,pcd,bin,xyz}   any point file read_points() knows, or
//   velodyne/NNNNNN.bin               a KITTI odometry sequence (with poses.txt copied or linked
//                                     from KITTI's poses/NN.txt).
// In a velodyne/ sequence with a KITTI calib.txt, pose(i) is poses.txt's pose times calib.txt's
// "Tr" (KITTI's poses are the left camera's, its scans the Velodyne's). PCD viewpoints inside a
// sequence folder are ignored: poses.txt places the clouds. Clouds are in the sensor frame;
// use transform_to_world(pose(i), ...) to move them.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include "atomic_file.hpp"
#include "cloud.hpp"
#include "error.hpp"
#include "kitti.hpp"
#include "point_file.hpp"
#include "trajectory.hpp"

namespace knnocc::io {

// True if path is a directory holding a poses.txt file and a clouds/ or velodyne/ directory.
// Never throws.
inline bool is_sequence_dir(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path dir(path);
  return fs::is_directory(dir, ec) && fs::is_regular_file(dir / "poses.txt", ec) &&
         (fs::is_directory(dir / "clouds", ec) || fs::is_directory(dir / "velodyne", ec));
}

class Sequence {
 public:
  // Reads poses.txt (and calib.txt) and lists the clouds; the clouds themselves load lazily.
  static Sequence open(const std::string& dir) {
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::path root(dir);
    if (!fs::is_directory(root, ec))
      throw Error(dir, fs::exists(root, ec) ? "is not a folder: a sequence is a folder holding "
                                              "poses.txt and clouds/ (or velodyne/)"
                                            : "sequence folder does not exist");
    const fs::path poses_file = root / "poses.txt";
    if (!fs::is_regular_file(poses_file, ec)) {
      throw Error(poses_file.string(), "missing poses.txt in sequence folder");
    }
    fs::path cloud_dir = root / "clouds";
    if (!fs::is_directory(cloud_dir, ec)) cloud_dir = root / "velodyne";
    if (!fs::is_directory(cloud_dir, ec)) {
      throw Error((root / "clouds").string(),
                  "missing clouds/ (or velodyne/) folder in sequence folder");
    }

    Sequence seq;
    seq.dir_ = dir;
    seq.poses_ = read_trajectory(poses_file.string());
    const fs::path calib = root / "calib.txt";
    if (cloud_dir.filename() == "velodyne" && !fs::is_regular_file(calib, ec)) {
      throw Error(calib.string(),
                  "missing: a velodyne/ sequence needs KITTI's calib.txt (its Tr takes the "
                  "Velodyne frame to the camera poses of poses.txt); for poses already in the "
                  "scanner's frame name the folder clouds/");
    }
    if (cloud_dir.filename() == "velodyne") {
      seq.tr_ = read_kitti_calib_tr(calib.string());
      for (Pose& p : seq.poses_) p = seq.scanner_pose(p);
    }
    for (fs::directory_iterator it(cloud_dir, ec), end; !ec && it != end; it.increment(ec)) {
      std::error_code type_ec;  // a file vanishing mid-listing is not a listing error
      const std::string ext = it->path().extension().string();
      if ((ext == ".ply" || ext == ".pcd" || ext == ".bin" || ext == ".xyz") &&
          !it->is_directory(type_ec)) {
        seq.clouds_.push_back(it->path().string());
      }
    }
    if (ec) throw Error(cloud_dir.string(), "cannot list folder: " + ec.message());
    // Directory order is arbitrary; zero-padded names make name order the pose order.
    std::sort(seq.clouds_.begin(), seq.clouds_.end());

    if (seq.clouds_.empty()) {
      throw Error(cloud_dir.string(), "no .ply, .pcd, .bin or .xyz clouds in folder");
    }
    if (seq.clouds_.size() != seq.poses_.size()) {
      throw Error(dir, "poses.txt has " + std::to_string(seq.poses_.size()) + " poses but " +
                           cloud_dir.filename().string() + "/ has " +
                           std::to_string(seq.clouds_.size()) + " clouds");
    }
    return seq;
  }

  std::size_t size() const noexcept { return clouds_.size(); }
  const std::string& dir() const noexcept { return dir_; }

  const Pose& pose(std::size_t i) const {
    check(i);
    return poses_[i];
  }
  const std::vector<Pose>& poses() const noexcept { return poses_; }

  std::string cloud_path(std::size_t i) const {
    check(i);
    return clouds_[i];
  }

  /// A pose given as poses.txt gives it (e.g. a corrected pose) as pose() gives it: times
  /// calib.txt's Tr in a velodyne/ sequence, unchanged otherwise.
  Pose scanner_pose(Pose p) const {
    if (!tr_) return p;
    p.t = p.q * tr_->translation() + p.t;
    p.q = (p.q * Eigen::Quaterniond(tr_->rotation())).normalized();
    return p;
  }

  // Cloud i in the sensor frame.
  Cloud load_cloud(std::size_t i) const { return read_points(cloud_path(i)); }

 private:
  Sequence() = default;

  void check(std::size_t i) const {
    if (i >= clouds_.size()) {
      throw Error(dir_, "index " + std::to_string(i) + " out of range (sequence has " +
                            std::to_string(clouds_.size()) + " clouds)");
    }
  }

  std::string dir_;
  std::vector<Pose> poses_;
  std::vector<std::string> clouds_;
  std::optional<Eigen::Isometry3d> tr_;  // calib.txt's Tr (velodyne/ sequences)
};

// The points of a keyframe within max_range of its sensor (max_range <= 0: all of them), in the
// world frame and in double (R * p + t); `ids` gets the ids of the kept points when the cloud has
// ids, and is left empty otherwise; `evidence` (optional) likewise gets the kept points' SLAM
// counters when the cloud has them. The k-NN tracker's input.
inline void keyframe_to_world(const Pose& pose, const Cloud& cloud, double max_range,
                              std::vector<Point3d>& world, std::vector<std::uint64_t>& ids,
                              std::vector<PointEvidence>* evidence = nullptr) {
  world.clear();
  ids.clear();
  if (evidence) evidence->clear();
  const Eigen::Matrix3d R = pose.q.toRotationMatrix();
  for (std::size_t j = 0; j < cloud.points.size(); ++j) {
    const Point3f& p = cloud.points[j];
    if (max_range > 0.0 &&
        !(std::sqrt(double(p.x) * p.x + double(p.y) * p.y + double(p.z) * p.z) <= max_range))
      continue;
    const Eigen::Vector3d w = R * Eigen::Vector3d(p.x, p.y, p.z) + pose.t;
    world.push_back(Point3d{w.x(), w.y(), w.z()});
    if (!cloud.ids.empty()) ids.push_back(cloud.ids[j]);
    if (evidence && !cloud.evidence.empty()) evidence->push_back(cloud.evidence[j]);
  }
}

// Writes a sequence folder that Sequence::open reads back: clouds/NNNNNN.ply (binary, float xyz,
// plus uint ids and uchar red green blue when the clouds have them) and poses.txt, written last, so
// a folder interrupted half-way is not mistaken for a sequence. Each file is written atomically.
inline void write_sequence(const std::string& dir, const std::vector<Pose>& poses,
                           const std::vector<const Cloud*>& clouds) {
  namespace fs = std::filesystem;
  if (poses.size() != clouds.size())
    throw Error(dir, "write_sequence: " + std::to_string(poses.size()) + " poses for " +
                         std::to_string(clouds.size()) + " clouds");
  std::error_code ec;
  fs::create_directories(fs::path(dir) / "clouds", ec);
  if (ec) throw Error(dir, "cannot create folder: " + ec.message());
  for (std::size_t i = 0; i < clouds.size(); ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "%06zu.ply", i);
    write_ply_cloud((fs::path(dir) / "clouds" / name).string(), *clouds[i]);
  }
  std::string text = "# stamp tx ty tz qx qy qz qw (sensor to world)\n";
  for (const Pose& p : poses) {
    char line[256];
    std::snprintf(line, sizeof line, "%.6f %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", p.stamp,
                  p.t.x(), p.t.y(), p.t.z(), p.q.x(), p.q.y(), p.q.z(), p.q.w());
    text += line;
  }
  AtomicFile out((fs::path(dir) / "poses.txt").string());
  out.write(text);
  out.commit();
}

}  // namespace knnocc::io
