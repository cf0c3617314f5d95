// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// knnocc's keyframe exporter for ORB-SLAM2 and ORB-SLAM3: one header to add to an ORB-SLAM
// build. It writes the sequence folder `knnocc map` reads, while SLAM runs:
//
//   DIR/poses.txt                     "stamp tx ty tz qx qy qz qw" per keyframe: camera to world
//                                     (KeyFrame::GetPoseInverse) when the keyframe was written
//   DIR/clouds/NNNNNN.ply             the keyframe's map points (GetMapPointMatches, null and bad
//                                     ones skipped) in the camera frame, binary PLY: float x y z,
//                                     uint id (MapPoint::mnId), and the point's evidence then:
//                                     uint found (GetFound), visible (found / GetFoundRatio),
//                                     observations (GetObservations().size(): keyframes that see
//                                     it; Observations() counts a stereo one twice)
//   DIR/corrections/after_NNNNNN.txt  after each loop closure or global bundle adjustment (ORB-SLAM
//                                     raises Map::GetLastBigChangeIdx for both), and at finish():
//                                     the poses of keyframes 0..NNNNNN then, for `--corrections`
//
// Use (ORB-SLAM2: Map*; ORB-SLAM3: the Atlas's current Map*):
//
//   #include "knnocc_orbslam_export.hpp"
//   knnocc::orbslam::KeyframeExporter exporter("run1");      // creates run1/clouds, corrections
//   while (...) { slam.TrackStereo(left, right, t); exporter.update(map); }
//   slam.Shutdown();
//   exporter.finish(map);                                    // the last keyframes, final poses
//   // knnocc map --input run1 --corrections run1/corrections --res 0.05 -o run1.bt
//
// ORB-SLAM's System keeps its map private: add `Map* GetMap() { return mpMap; }` to System
// (ORB-SLAM3: `Map* GetMap() { return mpAtlas->GetCurrentMap(); }`), or call update() from
// inside System. update() may run on any thread: it holds Map::mMutexMapUpdate (the lock under
// which loop closing and global BA move keyframes and points) while it reads the map.
//
// A keyframe is written once `lag` newer keyframes exist (local mapping still adds map points to
// recent keyframes), with its points and their evidence at that moment; the points are stored in
// the camera frame, so a later correction of the keyframe's pose moves them with it. A keyframe
// that ORB-SLAM culls after it was written keeps the last pose the exporter saw. One map is
// followed: when ORB-SLAM3 starts a new map in its Atlas, start a new exporter.
//
// Both APIs are told apart by their types: cv::Mat poses and positions (ORB-SLAM2) or
// Sophus::SE3f and Eigen::Vector3f (ORB-SLAM3). Needs C++11, Eigen and POSIX (as both build).
// File errors throw std::runtime_error naming the file; every file is written to a temporary
// beside it and renamed, so a reader never sees half a file.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include <errno.h>
#include <sys/stat.h>

namespace knnocc {
namespace orbslam {

struct ExportOptions {
  /// A keyframe is written once this many newer keyframes exist (all of them at finish()).
  std::size_t lag = 5;
};

namespace detail {

struct Pose {  // camera to world
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  bool operator==(const Pose& o) const { return R == o.R && t == o.t; }
};

// ORB-SLAM2: a 4x4 CV_32F cv::Mat.
template <class Mat>
auto to_pose(const Mat& T, int) -> decltype(T.template at<float>(0, 0), Pose()) {
  Pose p;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) p.R(r, c) = T.template at<float>(r, c);
    p.t(r) = T.template at<float>(r, 3);
  }
  return p;
}
// ORB-SLAM3: Sophus::SE3f.
template <class SE3>
auto to_pose(const SE3& T, long) -> decltype(T.rotationMatrix(), T.translation(), Pose()) {
  Pose p;
  p.R = T.rotationMatrix().template cast<double>();
  p.t = T.translation().template cast<double>();
  return p;
}
// ORB-SLAM2: a 3x1 CV_32F cv::Mat; ORB-SLAM3: Eigen::Vector3f.
template <class Mat>
auto to_point(const Mat& X, int) -> decltype(X.template at<float>(0), Eigen::Vector3d()) {
  return {X.template at<float>(0), X.template at<float>(1), X.template at<float>(2)};
}
template <class Vec>
auto to_point(const Vec& X, long) -> decltype(X.x(), Eigen::Vector3d()) {
  return {X.x(), X.y(), X.z()};
}

inline void store_le(std::string& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out += static_cast<char>((v >> (8 * i)) & 0xffu);
}
inline void store_le(std::string& out, float f) {
  std::uint32_t v = 0;
  static_assert(sizeof v == sizeof f, "float is 32 bits");
  std::memcpy(&v, &f, sizeof v);
  store_le(out, v);
}

// Writes `bytes` to a temporary beside `path` and renames it over `path`.
inline void write_file(const std::string& path, const std::string& bytes) {
  const std::string tmp = path + ".tmp-knnocc";
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw std::runtime_error(tmp + ": cannot create the file");
  const bool written = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
  if (std::fclose(f) != 0 || !written || std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw std::runtime_error(path + ": cannot write the file");
  }
}

// Creates `dir` and its missing parents (mkdir -p); std::runtime_error naming it otherwise.
inline void make_dirs(const std::string& dir) {
  for (std::size_t at = 1; at <= dir.size(); ++at) {
    if (at < dir.size() && dir[at] != '/') continue;
    const std::string part = dir.substr(0, at);
    struct stat st;
    if (::mkdir(part.c_str(), 0777) != 0 &&
        !(errno == EEXIST && ::stat(part.c_str(), &st) == 0 && S_ISDIR(st.st_mode)))
      throw std::runtime_error(part + ": cannot create the folder: " + std::strerror(errno));
  }
}

inline std::string pose_line(double stamp, const Pose& p) {
  const Eigen::Quaterniond q(p.R);
  char line[256];
  std::snprintf(line, sizeof line, "%.6f %.9g %.9g %.9g %.9g %.9g %.9g %.9g\n", stamp, p.t.x(),
                p.t.y(), p.t.z(), q.x(), q.y(), q.z(), q.w());
  return line;
}

}  // namespace detail

class KeyframeExporter {
 public:
  explicit KeyframeExporter(const std::string& dir, ExportOptions options = {})
      : dir_(dir), options_(options) {
    detail::make_dirs(dir_ + "/clouds");
    detail::make_dirs(dir_ + "/corrections");
  }

  /// Writes the keyframes that have `lag` newer ones, and a correction snapshot when ORB-SLAM
  /// reported a loop closure or global BA since the last call.
  template <class Map>
  void update(Map* map) {
    export_keyframes(map, options_.lag);
  }

  /// Writes every remaining keyframe and, when any keyframe's pose changed since it was written,
  /// a last snapshot with the final poses (the map `--corrections` builds is then the map of
  /// the final trajectory).
  template <class Map>
  void finish(Map* map) {
    export_keyframes(map, 0);
    bool moved = false;
    for (const Written& w : written_) moved = moved || !(w.current == w.written);
    if (moved) write_snapshot();
  }

  /// Keyframes written so far (the clouds in DIR/clouds).
  std::size_t keyframes() const { return written_.size(); }
  /// Correction snapshots written so far.
  std::size_t snapshots() const { return snapshots_; }

 private:
  struct Written {
    unsigned long id;  // KeyFrame::mnId
    double stamp;
    detail::Pose written, current;
  };

  template <class Map>
  void export_keyframes(Map* map, std::size_t lag) {
    std::unique_lock<std::mutex> lock(map->mMutexMapUpdate);
    auto keyframes = map->GetAllKeyFrames();
    typedef typename decltype(keyframes)::value_type KeyFramePtr;
    keyframes.erase(std::remove_if(keyframes.begin(), keyframes.end(),
                                   [](KeyFramePtr kf) { return kf->isBad(); }),
                    keyframes.end());
    std::sort(keyframes.begin(), keyframes.end(),
              [](KeyFramePtr a, KeyFramePtr b) { return a->mnId < b->mnId; });
    std::size_t fresh = 0;  // keyframes not written yet (they follow the written ones by mnId)
    for (auto* kf : keyframes) {
      const auto at = index_.find(kf->mnId);
      if (at == index_.end())
        ++fresh;
      else
        written_[at->second].current = detail::to_pose(kf->GetPoseInverse(), 0);
    }
    const std::size_t first_new = keyframes.size() - fresh;
    const std::size_t count = fresh > lag ? fresh - lag : 0;
    for (std::size_t i = first_new; i < first_new + count; ++i) write_keyframe(*keyframes[i]);
    if (count > 0) write_poses();
    const int big_change = map->GetLastBigChangeIdx();
    if (big_change != big_change_ && !written_.empty()) write_snapshot();
    big_change_ = big_change;
  }

  template <class KeyFrame>
  void write_keyframe(KeyFrame& kf) {
    const detail::Pose twc = detail::to_pose(kf.GetPoseInverse(), 0);
    const Eigen::Matrix3d rcw = twc.R.transpose();
    std::string body;
    std::size_t n = 0;
    for (auto* mp : kf.GetMapPointMatches()) {
      if (!mp || mp->isBad()) continue;
      const Eigen::Vector3d xc = rcw * (detail::to_point(mp->GetWorldPos(), 0) - twc.t);
      for (int a = 0; a < 3; ++a) detail::store_le(body, static_cast<float>(xc(a)));
      const int found = mp->GetFound();
      const float ratio = mp->GetFoundRatio();
      const long visible = ratio > 0 ? std::lround(found / ratio) : 0;
      if (mp->mnId > 0xFFFFFFFFul) throw std::runtime_error(dir_ + ": a map point id past 2^32");
      detail::store_le(body, static_cast<std::uint32_t>(mp->mnId));
      detail::store_le(body, static_cast<std::uint32_t>(std::max(found, 0)));
      detail::store_le(body, static_cast<std::uint32_t>(std::max(visible, 0L)));
      detail::store_le(body, static_cast<std::uint32_t>(mp->GetObservations().size()));
      ++n;
    }
    const std::string header =
        "ply\nformat binary_little_endian 1.0\ncomment ORB-SLAM keyframe " +
        std::to_string(kf.mnId) + ", map points in the camera frame\nelement vertex " +
        std::to_string(n) +
        "\nproperty float x\nproperty float y\nproperty float z\nproperty uint id\n"
        "property uint found\nproperty uint visible\nproperty uint observations\nend_header\n";
    char name[32];
    std::snprintf(name, sizeof name, "%06zu.ply", written_.size());
    detail::write_file(dir_ + "/clouds/" + name, header + body);
    index_.emplace(kf.mnId, written_.size());
    written_.push_back({kf.mnId, kf.mTimeStamp, twc, twc});
  }

  void write_poses() const {
    std::string text = "# stamp tx ty tz qx qy qz qw (camera to world when written)\n";
    for (const Written& w : written_) text += detail::pose_line(w.stamp, w.written);
    detail::write_file(dir_ + "/poses.txt", text);
  }

  void write_snapshot() {
    std::string text = "# stamp tx ty tz qx qy qz qw (camera to world after a correction)\n";
    for (const Written& w : written_) text += detail::pose_line(w.stamp, w.current);
    char name[40];
    std::snprintf(name, sizeof name, "after_%06zu.txt", written_.size() - 1);
    detail::write_file(dir_ + "/corrections/" + name, text);
    ++snapshots_;
  }

  std::string dir_;
  ExportOptions options_;
  std::vector<Written> written_;                // in the order of the clouds
  std::map<unsigned long, std::size_t> index_;  // mnId -> cloud index
  int big_change_ = 0;                          // Map::GetLastBigChangeIdx seen last
  std::size_t snapshots_ = 0;
};

}  // namespace orbslam
}  // namespace knnocc
