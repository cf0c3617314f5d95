// Sequence folders (io/sequence.hpp), and the real datasets read as sequences.

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <knnocc/io/cloud.hpp>
#include <knnocc/io/error.hpp>
#include <knnocc/io/ply.hpp>
#include <knnocc/io/point_file.hpp>
#include <knnocc/io/sequence.hpp>
#include <knnocc/io/trajectory.hpp>
#include <knnocc/io/voxel_list.hpp>
#include <knnocc/io/xyz.hpp>

#include "io_files.hpp"
#include "test_support.hpp"

namespace io = knnocc::io;
namespace fs = std::filesystem;
using knnocc::Point3f;
using namespace knnocc::test::io_files;

TEST_CASE("io.sequence folder") {
  ScratchDir dir("sequence");
  const fs::path root = dir.path() / "seq";
  fs::create_directories(root / "clouds");
  write_bytes((root / "poses.txt").string(),
              "# stamp tx ty tz qx qy qz qw\n0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n2 2 0 0 0 0 0 1\n");
  // Written out of order on purpose: open() must sort by name.
  for (const int i : {2, 0, 1}) {
    std::vector<Point3f> pts(static_cast<std::size_t>(i + 1), Point3f{float(i), 0, 0});
    char name[32];
    std::snprintf(name, sizeof name, "%06d.ply", i);
    io::write_ply((root / "clouds" / name).string(), pts);
  }
  write_bytes((root / "clouds" / "README.txt").string(), "not a cloud\n");

  CHECK(io::is_sequence_dir(root.string()));
  CHECK_FALSE(io::is_sequence_dir((root / "clouds").string()));
  CHECK_FALSE(io::is_sequence_dir(dir.file("nowhere")));

  const io::Sequence seq = io::Sequence::open(root.string());
  REQUIRE(seq.size() == 3);
  for (std::size_t i = 0; i < 3; ++i) {
    CHECK(seq.pose(i).t.x() == double(i));
    CHECK(fs::path(seq.cloud_path(i)).filename().string().substr(0, 6) ==
          "00000" + std::to_string(i));
    const io::Cloud c = seq.load_cloud(i);
    REQUIRE(c.points.size() == i + 1);
    CHECK(c.points[0].x == float(i));
  }
  CHECK_THROWS_AS(seq.pose(3), io::Error);

  const auto open_error = [](const fs::path& d) {
    return error_of([&] { io::Sequence::open(d.string()); });
  };
  CHECK(contains(open_error(dir.path() / "nowhere"), "does not exist"));

  // One extra cloud: counts differ.
  io::write_ply((root / "clouds" / "000003.ply").string(), {Point3f{0, 0, 0}});
  std::string msg = open_error(root);
  CHECK(contains(msg, root.string()));
  CHECK(contains(msg, "poses.txt has 3 poses but clouds/ has 4 clouds"));

  // No clouds.
  for (int i = 0; i < 4; ++i) fs::remove(root / "clouds" / ("00000" + std::to_string(i) + ".ply"));
  CHECK(contains(open_error(root), "no .ply, .pcd, .bin or .xyz clouds"));

  fs::remove(root / "poses.txt");
  msg = open_error(root);
  CHECK(contains(msg, "poses.txt"));
  CHECK(contains(msg, "missing"));
  CHECK_FALSE(io::is_sequence_dir(root.string()));
}

namespace {
// The vertex count a PLY header declares, read independently of io::read_ply.
std::uint64_t header_vertex_count(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::string line;
  while (std::getline(f, line) && line.rfind("end_header", 0) != 0) {
    if (line.rfind("element vertex ", 0) == 0) return std::stoull(line.substr(15));
  }
  return 0;
}
}  // namespace

TEST_CASE("io.real data: TUM fr2/pioneer_slam2 sequence") {
  const std::string dir = knnocc::test::data_path("tum_fr2_pioneer_slam2");
  if (dir.empty()) {
    knnocc::test::skip("../shared/data/tum_fr2_pioneer_slam2 not found; skipping");
    return;
  }
  CHECK(io::is_sequence_dir(dir));
  const io::Sequence seq = io::Sequence::open(dir);
  REQUIRE(seq.size() == 10);
  const io::Cloud c = seq.load_cloud(0);
  const std::uint64_t declared = header_vertex_count(seq.cloud_path(0));
  CHECK(declared > 50000);
  CHECK(declared < 80000);
  CHECK(c.points.size() == declared);
  CHECK(c.ids.empty());
  std::size_t bad = 0;
  for (const Point3f& q : c.points) {
    if (!std::isfinite(q.x) || !std::isfinite(q.y) || !(q.z > 0.0f && q.z < 10.0f)) ++bad;
  }
  CHECK(bad == 0);
  // Ground-truth quaternions have 4 decimals: accepted and normalised.
  CHECK(seq.pose(0).q.norm() == doctest::Approx(1.0).epsilon(1e-12));
  CHECK(seq.pose(9).stamp > seq.pose(0).stamp);
}

TEST_CASE("io.real data: ORB-SLAM2 keyframes carry ids") {
  const std::string dir = knnocc::test::data_path("orbslam2_stereo_keyframes");
  if (dir.empty()) {
    knnocc::test::skip("../shared/data/orbslam2_stereo_keyframes not found; skipping");
    return;
  }
  const io::Sequence seq = io::Sequence::open(dir);
  CHECK(seq.size() == 249);
  const io::Cloud c = seq.load_cloud(0);
  CHECK(c.points.size() == 182);
  REQUIRE(c.ids.size() == 182);
  std::vector<std::uint64_t> sorted = c.ids;
  std::sort(sorted.begin(), sorted.end());
  CHECK(std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end());
  std::size_t bad = 0;
  for (const Point3f& q : c.points) {
    if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z)) ++bad;
  }
  CHECK(bad == 0);
}
