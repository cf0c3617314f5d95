// OctoMap .graph files (liboctomap as the oracle when found), KITTI scans, calibration and poses,
// TUM/KITTI trajectories, sequence folders with .pcd/.bin clouds, and ScanSource.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <knnocc/io/kitti.hpp>
#include <knnocc/io/pcd.hpp>
#include <knnocc/io/ply.hpp>
#include <knnocc/io/scan_graph.hpp>
#include <knnocc/io/scan_source.hpp>
#include <knnocc/io/sequence.hpp>
#include <knnocc/io/trajectory.hpp>

#include "test_support.hpp"

#if KNNOCC_HAVE_OCTOMAP
#include <octomap/ScanGraph.h>
#endif

namespace io = knnocc::io;
namespace fs = std::filesystem;
using knnocc::Point3f;

using knnocc::test::append_le;
using knnocc::test::read_file;
using knnocc::test::write_file;

namespace {

fs::path sources_file(const std::string& name) {
  return knnocc::test::scratch_dir("scan_sources") / name;
}

io::Pose make_pose(double x, double y, double z, double angle, Eigen::Vector3d axis) {
  io::Pose p;
  p.t = Eigen::Vector3d(x, y, z);
  p.q = Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis.normalized()));
  return p;
}

io::ScanGraph sample_graph() {
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

void check_graph_error(const std::string& name, const std::string& bytes,
                       const std::string& needle) {
  CAPTURE(name);
  const fs::path path = sources_file(name);
  write_file(path, bytes);
  knnocc::test::reset_largest_allocation();
  try {
    (void)io::read_scan_graph(path.string());
    FAIL("no error");
  } catch (const io::Error& e) {
    const std::size_t largest = knnocc::test::largest_allocation();
    CHECK(largest < bytes.size() + 4096);
    CHECK(e.file() == path.string());
    CHECK_MESSAGE(e.problem().find(needle) != std::string::npos, e.problem());
  }
}

}  // namespace

TEST_CASE("scan_graph.round trip") {
  const io::ScanGraph g = sample_graph();
  const std::string path = sources_file("sample.graph").string();
  io::write_scan_graph(path, g);
  const io::ScanGraph back = io::read_scan_graph(path);
  REQUIRE(back.nodes.size() == 3);
  for (std::size_t i = 0; i < 3; ++i) {
    CHECK(back.nodes[i].id == g.nodes[i].id);
    CHECK(back.nodes[i].pose.t == g.nodes[i].pose.t);
    CHECK(back.nodes[i].pose.q.coeffs() == g.nodes[i].pose.q.coeffs());
    REQUIRE(back.nodes[i].points.size() == g.nodes[i].points.size());
    for (std::size_t k = 0; k < g.nodes[i].points.size(); ++k) {
      const Point3f &a = back.nodes[i].points[k], &b = g.nodes[i].points[k];
      CHECK(((a.x == b.x && a.y == b.y && a.z == b.z) || (std::isnan(a.y) && std::isnan(b.y))));
    }
  }
  REQUIRE(back.edges.size() == 1);
  CHECK(back.edges[0].second == 11);
  CHECK(back.edges[0].weight == 0.25);
  // Written again: the same bytes.
  const std::string again = sources_file("again.graph").string();
  io::write_scan_graph(again, back);
  CHECK(read_file(again) == read_file(path));
}

TEST_CASE("scan_graph.malformed files") {
  const std::string path = sources_file("good.graph").string();
  io::write_scan_graph(path, sample_graph());
  const std::string good = read_file(path);
  check_graph_error("empty.graph", "", "truncated while reading node count");
  check_graph_error("truncated.graph", good.substr(0, good.size() - 100), "truncated");
  check_graph_error("trailing.graph", good + "x", "unexpected bytes");
  std::string huge;
  append_le(huge, std::uint32_t{4000000000u});
  huge.append(200, '\0');
  check_graph_error("huge_nodes.graph", huge, "node count is 4000000000");
  std::string points;
  append_le(points, std::uint32_t{1});
  append_le(points, std::uint32_t{3000000000u});
  points.append(100, '\0');
  check_graph_error("huge_points.graph", points, "point count is 3000000000");
  std::string marker = good;
  marker[8] = 4;  // first point's "3"
  check_graph_error("marker.graph", marker, "size marker 4 instead of 3");
  // Node 0's pose: after 4 + 4 + 100 * 28 bytes; translation marker, 3 doubles, rotation marker.
  const std::size_t pose0 = 8 + 100 * 28;
  std::string nan_pose = good;
  const double nan = std::nan("");
  std::memcpy(&nan_pose[pose0 + 4], &nan, 8);
  check_graph_error("nan_pose.graph", nan_pose, "node 0: non-finite pose value");
  std::string bad_q = good;
  const double two = 2.0;
  std::memcpy(&bad_q[pose0 + 32], &two, 8);
  check_graph_error("bad_quaternion.graph", bad_q, "quaternion norm");
  io::ScanGraph dup = sample_graph();
  dup.nodes[2].id = dup.nodes[0].id;
  io::write_scan_graph(path, dup);
  check_graph_error("dup.graph", read_file(path), "two nodes have the id 1");
  io::ScanGraph dangling = sample_graph();
  dangling.edges[0].second = 99;
  io::write_scan_graph(path, dangling);
  check_graph_error("dangling.graph", read_file(path), "edge 0 refers to unknown node id 99");
}

#if KNNOCC_HAVE_OCTOMAP
TEST_CASE("scan_graph.liboctomap reads ours and we read liboctomap's") {
  // liboctomap -> us
  octomap::ScanGraph theirs;
  knnocc::test::Rng rng(8);
  std::uniform_real_distribution<float> u(-5.f, 5.f);
  std::vector<octomap::ScanNode*> nodes;
  for (int i = 0; i < 4; ++i) {
    auto* pc = new octomap::Pointcloud();
    for (int k = 0; k < 50 * (i + 1); ++k) pc->push_back(u(rng), u(rng), u(rng));
    nodes.push_back(theirs.addNode(pc, octomap::pose6d(i, -i, 0.5 * i, 0.1 * i, 0.2, -0.3 * i)));
  }
  theirs.addEdge(nodes[0], nodes[3], octomap::pose6d(1, 2, 3, 0, 0, 0.5));
  const std::string path = sources_file("octomap.graph").string();
  REQUIRE(theirs.writeBinary(path));
  const io::ScanGraph ours = io::read_scan_graph(path);
  REQUIRE(ours.nodes.size() == 4);
  for (std::size_t i = 0; i < 4; ++i) {
    const octomap::ScanNode& n = *nodes[i];
    CHECK(ours.nodes[i].id == n.id);
    REQUIRE(ours.nodes[i].points.size() == n.scan->size());
    std::size_t differing = 0;
    for (std::size_t k = 0; k < n.scan->size(); ++k) {
      const octomap::point3d& p = (*n.scan)[k];
      const Point3f& q = ours.nodes[i].points[k];
      differing += p.x() != q.x || p.y() != q.y || p.z() != q.z;
    }
    CHECK(differing == 0);
    CHECK(ours.nodes[i].pose.t.x() == n.pose.trans().x());
    CHECK(ours.nodes[i].pose.q.w() == n.pose.rot().u());
    CHECK(ours.nodes[i].pose.q.z() == n.pose.rot().z());
  }
  REQUIRE(ours.edges.size() == 1);
  CHECK(ours.edges[0].first == nodes[0]->id);
  CHECK(ours.edges[0].second == nodes[3]->id);

  // us -> liboctomap
  const std::string mine = sources_file("ours.graph").string();
  io::write_scan_graph(mine, sample_graph());
  octomap::ScanGraph read;
  REQUIRE(read.readBinary(mine));
  REQUIRE(read.size() == 3);
  const io::ScanGraph g = sample_graph();
  std::size_t i = 0;
  for (auto it = read.begin(); it != read.end(); ++it, ++i) {
    CHECK((*it)->id == g.nodes[i].id);
    CHECK((*it)->scan->size() == g.nodes[i].points.size());
    CHECK((*it)->pose.trans().y() == doctest::Approx(g.nodes[i].pose.t.y()));
    CHECK((*it)->pose.rot().u() == doctest::Approx(g.nodes[i].pose.q.w()));
    CHECK((*(*it)->scan)[7].x() == g.nodes[i].points[7].x);
  }
  CHECK(read.edges_end() - read.edges_begin() == 1);
}
#endif

TEST_CASE("kitti.velodyne bin, calib and poses") {
  const std::vector<Point3f> pts = {{1.5f, -2.f, 0.25f}, {100.f, 0.f, -3.f}};
  const std::string bin = sources_file("000000.bin").string();
  io::write_kitti_bin(bin, pts);
  CHECK(fs::file_size(bin) == 32);
  const io::Cloud c = io::read_points(bin);
  REQUIRE(c.points.size() == 2);
  CHECK(c.points[1].x == 100.f);
  CHECK(c.points[0].z == 0.25f);
  write_file(bin, std::string(33, '\0'));
  CHECK_THROWS_WITH_AS(io::read_kitti_bin(bin), doctest::Contains("not a multiple of 16"),
                       io::Error);

  const std::string calib = sources_file("calib.txt").string();
  write_file(calib, "P0: 1 0 0 0 0 1 0 0 0 0 1 0\nTr: 0 -1 0 0.1 0 0 -1 0.2 1 0 0 0.3\n");
  const Eigen::Isometry3d tr = io::read_kitti_calib_tr(calib);
  CHECK((tr * Eigen::Vector3d(1, 0, 0) - Eigen::Vector3d(0.1, 0.2, 1.3)).norm() < 1e-12);
  write_file(calib, "P0: 1 0 0 0 0 1 0 0 0 0 1 0\n");
  CHECK_THROWS_WITH_AS(io::read_kitti_calib_tr(calib), doctest::Contains("no 'Tr:' line"),
                       io::Error);
  write_file(calib, "Tr: 2 0 0 0 0 1 0 0 0 0 1 0\n");
  CHECK_THROWS_WITH_AS(io::read_kitti_calib_tr(calib), doctest::Contains("not a rotation"),
                       io::Error);

  const std::string poses = sources_file("kitti_poses.txt").string();
  write_file(poses,
             "1.000000e+00 0.000000e+00 0.000000e+00 0.000000e+00 0.000000e+00 1.000000e+00 "
             "0.000000e+00 0.000000e+00 0.000000e+00 0.000000e+00 1.000000e+00 0.000000e+00\n"
             "0 -1 0 5 1 0 0 6 0 0 1 7\n");
  const auto p = io::read_trajectory(poses);
  REQUIRE(p.size() == 2);
  CHECK(p[1].stamp == 1.0);
  CHECK(p[1].t == Eigen::Vector3d(5, 6, 7));
  CHECK((p[1].q * Eigen::Vector3d(1, 0, 0) - Eigen::Vector3d(0, 1, 0)).norm() < 1e-12);
  write_file(poses, "1 0 0 0 0 1 0 0 0 0 1\n");
  CHECK_THROWS_WITH_AS(io::read_kitti_poses(poses), doctest::Contains("expected 12 numbers"),
                       io::Error);
  write_file(poses, "1 0 0 0 0 1 0 0 0 0 -1 0\n");  // a reflection
  CHECK_THROWS_WITH_AS(io::read_trajectory(poses), doctest::Contains("line 1: the 3x3 part"),
                       io::Error);
}

TEST_CASE("trajectory.TUM and KITTI written and read back") {
  std::vector<io::Pose> poses;
  for (int i = 0; i < 5; ++i) {
    io::Pose p = make_pose(0.1 * i, -2.5 * i, 1e3 + i, 0.7 * i, Eigen::Vector3d(1, 2, 3));
    p.stamp = 1305031102.175304 + i;
    poses.push_back(p);
  }
  const std::string tum = sources_file("tum.txt").string(),
                    kitti = sources_file("kitti.txt").string();
  io::write_tum_poses(tum, poses);
  io::write_kitti_poses(kitti, poses);
  const auto a = io::read_trajectory(tum), b = io::read_trajectory(kitti);
  REQUIRE(a.size() == 5);
  REQUIRE(b.size() == 5);
  for (std::size_t i = 0; i < 5; ++i) {
    CHECK(a[i].stamp == poses[i].stamp);
    CHECK(a[i].t == poses[i].t);
    CHECK(a[i].q.angularDistance(poses[i].q) < 1e-12);
    CHECK(b[i].stamp == double(i));
    CHECK(b[i].t == poses[i].t);
    CHECK(b[i].q.angularDistance(poses[i].q) < 1e-9);
  }
}

TEST_CASE("sequence folders with .pcd and KITTI velodyne clouds; ScanSource") {
  const fs::path root = sources_file("seq_pcd");
  fs::remove_all(root);
  fs::create_directories(root / "clouds");
  write_file(root / "poses.txt", "0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n");
  io::write_pcd((root / "clouds" / "000000.pcd").string(), {{1, 2, 3}}, nullptr,
                io::PcdData::binary_compressed);
  io::write_ply((root / "clouds" / "000001.ply").string(), {{4, 5, 6}, {7, 8, 9}});
  write_file(root / "calib.txt",
             "fx 525 fy 525\n");  // not KITTI's: only velodyne/ folders use it
  const io::ScanSource src = io::ScanSource::open(root.string());
  CHECK(std::string(src.kind()) == "sequence folder");
  REQUIRE(src.size() == 2);
  CHECK(src.load(0).cloud.points[0].z == 3.f);
  CHECK(src.load(1).cloud.points.size() == 2);
  CHECK(src.load(1).pose.t.x() == 1.0);

  // KITTI layout: velodyne/*.bin, KITTI poses, calib.txt's Tr applied to every pose.
  const fs::path kitti = sources_file("kitti_seq");
  fs::remove_all(kitti);
  fs::create_directories(kitti / "velodyne");
  io::write_kitti_bin((kitti / "velodyne" / "000000.bin").string(), {{1, 0, 0}});
  io::write_kitti_bin((kitti / "velodyne" / "000001.bin").string(), {{1, 0, 0}});
  write_file(kitti / "poses.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n0 -1 0 5 1 0 0 6 0 0 1 7\n");
  write_file(kitti / "calib.txt", "Tr: 0 -1 0 0.1 0 0 -1 0.2 1 0 0 0.3\n");
  CHECK(io::is_sequence_dir(kitti.string()));
  const io::ScanSource ks = io::ScanSource::open(kitti.string());
  REQUIRE(ks.size() == 2);
  const io::Scan s1 = ks.load(1);
  std::vector<Point3f> world;
  io::transform_to_world(s1.pose, s1.cloud.points, world);
  // Tr * (1,0,0) = (0.1, 0.2, 1.3); the pose rotates x -> y, y -> -x and adds (5, 6, 7).
  CHECK(world[0].x == doctest::Approx(5 - 0.2));
  CHECK(world[0].y == doctest::Approx(6 + 0.1));
  CHECK(world[0].z == doctest::Approx(7 + 1.3));

  // A single PCD file: its VIEWPOINT is the sensor pose.
  const fs::path pcd = sources_file("viewpoint.pcd");
  write_file(pcd,
             "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nHEIGHT 1\n"
             "VIEWPOINT 10 20 30 0.7071067811865476 0 0 0.7071067811865476\nDATA ascii\n1 0 0\n");
  const io::ScanSource one = io::ScanSource::open(pcd.string());
  CHECK(std::string(one.kind()) == "point file");
  const io::Scan s = one.load(0);
  CHECK(s.pose.t == Eigen::Vector3d(10, 20, 30));
  CHECK((s.pose.q * Eigen::Vector3d(1, 0, 0) - Eigen::Vector3d(0, 1, 0)).norm() < 1e-12);
  CHECK(io::is_identity(io::ScanSource::open(root.string()).load(0).pose));

  // A .graph file.
  const std::string graph = sources_file("src.graph").string();
  io::write_scan_graph(graph, sample_graph());
  const io::ScanSource gs = io::ScanSource::open(graph);
  CHECK(std::string(gs.kind()) == "scan graph");
  REQUIRE(gs.size() == 3);
  CHECK(gs.load(2).cloud.points.size() == 102);
  CHECK_THROWS_AS(gs.load(3), io::Error);

  CHECK_THROWS_WITH_AS(io::ScanSource::open(sources_file("").string()),
                       doctest::Contains("not a sequence folder"), io::Error);
}
