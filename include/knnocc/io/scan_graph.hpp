// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// OctoMap's ScanGraph files (.graph): scans in the sensor frame with their sensor-to-world poses,
// plus pose-graph edges; what OctoMap's graph2tree turns into a .bt. Little-endian binary:
//
//   uint32 node count, then per node:
//     uint32 point count, per point: int32 3, float64 x y z
//     pose: int32 3, float64 tx ty tz; int32 4, float64 qw qx qy qz
//     uint32 id
//   uint32 edge count, then per edge: uint32 first id, uint32 second id, pose, float64 weight
//
// Reading checks every count against the bytes left before allocating, the 3/4 size markers,
// finite poses and quaternions of unit norm (within 1e-3; renormalised when off by more than
// 1e-6, so files written from float quaternions keep their exact values), unique node ids and
// edges between existing nodes; anything else is an io::Error naming the file. Points may be
// NaN (returned as read, narrowed to float).

#include <algorithm>
#include <cmath>
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

struct ScanNode {
  std::uint32_t id = 0;
  Pose pose;                    ///< sensor to world
  std::vector<Point3f> points;  ///< sensor frame
};

struct ScanEdge {
  std::uint32_t first = 0, second = 0;  ///< node ids
  Pose constraint;
  double weight = 1.0;
};

struct ScanGraph {
  std::vector<ScanNode> nodes;
  std::vector<ScanEdge> edges;
};

namespace detail {

class GraphReader {
 public:
  GraphReader(const std::string& path, const unsigned char* p, std::size_t n)
      : path_(path), p_(p), end_(p + n) {}

  std::size_t left() const { return static_cast<std::size_t>(end_ - p_); }
  std::uint64_t offset(const unsigned char* begin) const {
    return static_cast<std::uint64_t>(p_ - begin);
  }

  template <class T>
  T get(const char* what) {
    if (left() < sizeof(T)) {
      throw Error(path_, std::string("file truncated while reading ") + what + " (" +
                             std::to_string(left()) + " bytes left)");
    }
    const T v = load_le<T>(p_);
    p_ += sizeof(T);
    return v;
  }

  // A count of records of at least `min_bytes` each: checked against the bytes left.
  std::uint32_t count(const char* what, std::size_t min_bytes) {
    const std::uint32_t n = get<std::uint32_t>(what);
    if (n > left() / min_bytes) {
      throw Error(path_, std::string("file truncated: ") + what + " is " + std::to_string(n) +
                             " but only " + std::to_string(left()) + " bytes follow");
    }
    return n;
  }

  void marker(std::int32_t expected, const char* what) {
    const std::int32_t m = get<std::int32_t>(what);
    if (m != expected) {
      throw Error(path_, std::string("corrupt ") + what + ": size marker " + std::to_string(m) +
                             " instead of " + std::to_string(expected));
    }
  }

  Pose pose(const std::string& what) {
    Pose pose;
    marker(3, "pose translation");
    double v[7];
    for (int i = 0; i < 3; ++i) v[i] = get<double>("pose");
    marker(4, "pose rotation");
    for (int i = 3; i < 7; ++i) v[i] = get<double>("pose");
    for (double x : v) {
      if (!std::isfinite(x)) throw Error(path_, what + ": non-finite pose value");
    }
    pose.t = Eigen::Vector3d(v[0], v[1], v[2]);
    pose.q = Eigen::Quaterniond(v[3], v[4], v[5], v[6]);  // stored w x y z
    const double norm = pose.q.norm();
    if (!(std::abs(norm - 1.0) <= 1e-3)) {
      throw Error(path_, what + ": quaternion norm " + std::to_string(norm) + " is not 1");
    }
    if (std::abs(norm - 1.0) > 1e-6) pose.q.normalize();
    return pose;
  }

 private:
  const std::string& path_;
  const unsigned char* p_;
  const unsigned char* end_;
};

inline void put_pose(std::string& out, const Pose& pose) {
  char b[8];
  store_le(b, std::int32_t{3});
  out.append(b, 4);
  for (int i = 0; i < 3; ++i) {
    store_le(b, pose.t[i]);
    out.append(b, 8);
  }
  store_le(b, std::int32_t{4});
  out.append(b, 4);
  for (double v : {pose.q.w(), pose.q.x(), pose.q.y(), pose.q.z()}) {
    store_le(b, v);
    out.append(b, 8);
  }
}

}  // namespace detail

inline ScanGraph read_scan_graph(const std::string& path) {
  const detail::FileBuffer buf = detail::read_file(path);
  const auto* begin = reinterpret_cast<const unsigned char*>(buf.data());
  detail::GraphReader r(path, begin, buf.size());
  constexpr std::size_t kPoseBytes = 4 + 24 + 4 + 32;
  ScanGraph g;
  const std::uint32_t nodes = r.count("node count", 4 + kPoseBytes + 4);
  g.nodes.resize(nodes);
  for (std::uint32_t i = 0; i < nodes; ++i) {
    ScanNode& node = g.nodes[i];
    const std::uint32_t n = r.count("point count", 28);
    node.points.resize(n);
    for (std::uint32_t k = 0; k < n; ++k) {
      r.marker(3, "point");
      const double x = r.get<double>("point"), y = r.get<double>("point"),
                   z = r.get<double>("point");
      node.points[k] = Point3f{detail::to_float(x), detail::to_float(y), detail::to_float(z)};
    }
    node.pose = r.pose("node " + std::to_string(i));
    node.id = r.get<std::uint32_t>("node id");
  }
  std::vector<std::uint32_t> ids(nodes);
  for (std::uint32_t i = 0; i < nodes; ++i) ids[i] = g.nodes[i].id;
  std::sort(ids.begin(), ids.end());
  const auto repeated = std::adjacent_find(ids.begin(), ids.end());
  if (repeated != ids.end()) {
    throw Error(path, "two nodes have the id " + std::to_string(*repeated));
  }
  if (r.left() == 0) return g;  // some writers stop after the nodes
  const std::uint32_t edges = r.count("edge count", 8 + kPoseBytes + 8);
  g.edges.resize(edges);
  for (std::uint32_t i = 0; i < edges; ++i) {
    ScanEdge& e = g.edges[i];
    e.first = r.get<std::uint32_t>("edge");
    e.second = r.get<std::uint32_t>("edge");
    e.constraint = r.pose("edge " + std::to_string(i));
    e.weight = r.get<double>("edge weight");
    for (const std::uint32_t id : {e.first, e.second}) {
      if (!std::binary_search(ids.begin(), ids.end(), id)) {
        throw Error(
            path, "edge " + std::to_string(i) + " refers to unknown node id " + std::to_string(id));
      }
    }
  }
  if (r.left() != 0) {
    throw Error(path, std::to_string(r.left()) + " unexpected bytes after the last edge");
  }
  return g;
}

inline void write_scan_graph(const std::string& path, const ScanGraph& g) {
  std::string out;
  char b[8];
  auto put_u32 = [&](std::size_t v, const char* what) {
    if (v > 0xFFFFFFFFull) throw Error(path, std::string("write_scan_graph: too many ") + what);
    detail::store_le(b, static_cast<std::uint32_t>(v));
    out.append(b, 4);
  };
  put_u32(g.nodes.size(), "nodes");
  for (const ScanNode& node : g.nodes) {
    put_u32(node.points.size(), "points");
    out.reserve(out.size() + node.points.size() * 28 + 128);
    for (const Point3f& p : node.points) {
      detail::store_le(b, std::int32_t{3});
      out.append(b, 4);
      for (float v : {p.x, p.y, p.z}) {
        detail::store_le(b, static_cast<double>(v));
        out.append(b, 8);
      }
    }
    detail::put_pose(out, node.pose);
    put_u32(node.id, "ids");
  }
  put_u32(g.edges.size(), "edges");
  for (const ScanEdge& e : g.edges) {
    put_u32(e.first, "ids");
    put_u32(e.second, "ids");
    detail::put_pose(out, e.constraint);
    detail::store_le(b, e.weight);
    out.append(b, 8);
  }
  AtomicFile file(path);
  file.write(out);
  file.commit();
}

}  // namespace knnocc::io
