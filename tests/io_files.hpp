#pragma once
// Helpers shared by the io/ tests: a scratch folder per test case, byte-level file writing, the
// message of a thrown io::Error, and a point set with the float edge cases. `using namespace
// knnocc::test::io_files;` also brings io, fs, Point3f and test_support's file helpers.

#include <doctest/doctest.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <knnocc/core/point3.hpp>
#include <knnocc/io/error.hpp>
#include <knnocc/io/ply.hpp>
#include <knnocc/io/scan_graph.hpp>
#include <knnocc/io/trajectory.hpp>

#include <Eigen/Geometry>

#include "test_support.hpp"

namespace knnocc::test::io_files {

namespace io = knnocc::io;
namespace fs = std::filesystem;
using knnocc::Point3f;
using knnocc::test::append_le;
using knnocc::test::read_file;
using knnocc::test::write_file;

// A fresh directory per test case, unique per process so parallel runs (two compilers, ctest -j)
// never share files; removed on scope exit.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& name) {
    std::random_device rd;
    path_ = knnocc::test::scratch_dir("io") / (name + "_" + std::to_string(rd()));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;

  std::string file(const std::string& name) const { return (path_ / name).string(); }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

inline void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  REQUIRE(f.good());
}

inline std::string read_text(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::ostringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

inline bool host_little() {
  const std::uint16_t one = 1;
  unsigned char b = 0;
  std::memcpy(&b, &one, 1);
  return b == 1;
}

// Appends v in the requested byte order.
template <class T>
inline void put(std::string& s, T v, bool big_endian) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  if (big_endian == host_little()) std::reverse(b, b + sizeof(T));
  s.append(reinterpret_cast<const char*>(b), sizeof(T));
}

// Runs f and returns the io::Error message ("" if none was thrown).
template <class F>
inline std::string error_of(F&& f) {
  try {
    f();
  } catch (const io::Error& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("<not io::Error> ") + e.what();
  }
  return "<no exception>";
}

inline bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

// Writes `bytes` to a fresh file and checks read_ply throws io::Error naming the file and
// mentioning `expect`.
inline void check_ply_error(const ScratchDir& dir, const std::string& name,
                            const std::string& bytes, const std::string& expect) {
  const std::string p = dir.file(name);
  write_bytes(p, bytes);
  CAPTURE(name);
  CHECK_THROWS_AS(io::read_ply(p), io::Error);
  const std::string msg = error_of([&] { io::read_ply(p); });
  CAPTURE(msg);
  CHECK(contains(msg, p));
  CHECK(contains(msg, expect));
}

inline bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

inline std::vector<Point3f> sample_points() {
  std::vector<Point3f> pts;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-50.0f, 50.0f);
  for (int i = 0; i < 1000; ++i) pts.push_back(Point3f{u(rng), u(rng), u(rng)});
  pts.push_back(Point3f{0.0f, -0.0f, 1e-30f});
  pts.push_back(Point3f{std::numeric_limits<float>::max(), std::numeric_limits<float>::lowest(),
                        std::numeric_limits<float>::denorm_min()});
  return pts;
}

/// A file in the scratch folder of the scan-source tests.
inline fs::path sources_file(const std::string& name) {
  return knnocc::test::scratch_dir("scan_sources") / name;
}

/// A pose from a translation and a rotation by `angle` about `axis`.
inline io::Pose make_pose(double x, double y, double z, double angle, Eigen::Vector3d axis) {
  io::Pose p;
  p.t = Eigen::Vector3d(x, y, z);
  p.q = Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis.normalized()));
  return p;
}

/// A three-node scan graph with one edge and a NaN point.
inline io::ScanGraph sample_graph() {
  io::ScanGraph g;
  knnocc::test::Rng rng(21);
  std::uniform_real_distribution<float> u(-10.f, 10.f);
  for (std::uint32_t i = 0; i < 3; ++i) {
    io::ScanNode n;
    n.id = i * 10 + 1;
    n.pose = make_pose(i, 2.0 * i, 0.5, 0.3 * i, Eigen::Vector3d(0.2, 0.1, 1.0));
    for (int k = 0; k < 100 + static_cast<int>(i); ++k)
      n.points.push_back({u(rng), u(rng), u(rng)});
    g.nodes.push_back(n);
  }
  g.nodes[1].points[5].y = std::nanf("");
  io::ScanEdge e;
  e.first = 1;
  e.second = 11;
  e.constraint = make_pose(1, 2, 0, 0.3, Eigen::Vector3d::UnitZ());
  e.weight = 0.25;
  g.edges.push_back(e);
  return g;
}

}  // namespace knnocc::test::io_files
