// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// ScanSource: every input `knnocc map` takes, as a list of scans (a cloud in the sensor frame
// plus its sensor-to-world pose):
//   a sequence folder      poses.txt + clouds/ or velodyne/ (see sequence.hpp), one scan per cloud
//   an OctoMap .graph      one scan per node (scan_graph.hpp)
//   a single point file    .ply .pcd .bin .xyz .dat .txt: one scan, sensor at the origin; a PCD
//                          file's VIEWPOINT is its pose (PCL's convention: the points are in the
//                          sensor frame and the viewpoint places the sensor in the world)
// Scans load one at a time (a .graph file is read whole when opened).

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstddef>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <system_error>
#include <utility>

#include "cloud.hpp"
#include "error.hpp"
#include "pcd.hpp"
#include "point_file.hpp"
#include "scan_graph.hpp"
#include "sequence.hpp"
#include "trajectory.hpp"

namespace knnocc::io {

struct Scan {
  Pose pose;    ///< sensor to world
  Cloud cloud;  ///< sensor frame
};

class ScanSource {
 public:
  static ScanSource open(const std::string& path) {
    ScanSource s;
    s.path_ = path;
    if (is_sequence_dir(path)) {
      s.sequence_.emplace(Sequence::open(path));
      return s;
    }
    std::error_code ec;
    if (!std::filesystem::exists(path, ec))  // before the extension says anything
      throw Error(path,
                  "cannot open: " + (ec ? ec.message() : std::generic_category().message(ENOENT)));
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (ext == ".graph") {
      s.graph_ = std::make_shared<ScanGraph>(read_scan_graph(path));
      if (s.graph_->nodes.empty()) throw Error(path, "the scan graph has no scans");
    } else if (std::filesystem::is_directory(path)) {
      throw Error(path, "not a sequence folder (needs poses.txt and clouds/ or velodyne/)");
    }
    return s;
  }

  std::size_t size() const {
    if (sequence_) return sequence_->size();
    if (graph_) return graph_->nodes.size();
    return 1;
  }
  const std::string& path() const { return path_; }
  /// The whole graph when the source is a .graph file, else null.
  const ScanGraph* graph() const { return graph_.get(); }
  /// The sequence when the source is a sequence folder, else null.
  const Sequence* sequence() const { return sequence_ ? &*sequence_ : nullptr; }
  /// "sequence folder", "scan graph" or "point file".
  const char* kind() const {
    return sequence_ ? "sequence folder" : graph_ ? "scan graph" : "point file";
  }

  /// Scan i (0 <= i < size()); throws io::Error on a bad file.
  Scan load(std::size_t i) const {
    if (i >= size()) {
      throw Error(path_, "scan " + std::to_string(i) + " out of range (" + std::to_string(size()) +
                             " scans)");
    }
    Scan scan;
    if (sequence_) {
      scan.pose = sequence_->pose(i);
      scan.cloud = sequence_->load_cloud(i);
    } else if (graph_) {
      const ScanNode& node = graph_->nodes[i];
      scan.pose = node.pose;
      scan.cloud.points = node.points;
    } else if (is_pcd()) {
      PcdInfo info;
      scan.cloud = read_pcd(path_, &info);
      const double* v = info.viewpoint;
      scan.pose.t = Eigen::Vector3d(v[0], v[1], v[2]);
      scan.pose.q = Eigen::Quaterniond(v[3], v[4], v[5], v[6]);
      const double norm = scan.pose.q.norm();
      if (!(std::abs(norm - 1.0) <= 1e-3)) {
        throw Error(path_, "VIEWPOINT quaternion norm " + std::to_string(norm) + " is not 1");
      }
      scan.pose.q.normalize();
    } else {
      scan.cloud = read_points(path_);
    }
    return scan;
  }

 private:
  bool is_pcd() const {
    std::string ext = std::filesystem::path(path_).extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return ext == ".pcd";
  }

  std::string path_;
  std::optional<Sequence> sequence_;
  std::shared_ptr<const ScanGraph> graph_;
};

/// The farthest a sensor of the scans [first, last) of `source` goes from the origin along an
/// axis, from the poses alone (sequence folders and scan graphs; 0 for a point file): what
/// decides whether a run needs keys wider than OctoMap's 16 bits.
inline double sensor_reach(const ScanSource& source, std::size_t first, std::size_t last) {
  double reach = 0.0;
  if (const Sequence* seq = source.sequence())
    for (std::size_t i = first; i < last && i < seq->size(); ++i)
      reach = std::max(reach, seq->pose(i).t.cwiseAbs().maxCoeff());
  if (const ScanGraph* g = source.graph())
    for (std::size_t i = first; i < last && i < g->nodes.size(); ++i)
      reach = std::max(reach, g->nodes[i].pose.t.cwiseAbs().maxCoeff());
  return reach;
}

/// True when the pose is exactly the identity (no transform needed).
inline bool is_identity(const Pose& p) {
  return p.t.isZero(0.0) && p.q.w() == 1.0 && p.q.x() == 0.0 && p.q.y() == 0.0 && p.q.z() == 0.0;
}

}  // namespace knnocc::io
