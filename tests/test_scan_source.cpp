// ScanSource (io/scan_source.hpp): every input of knnocc map as posed scans, sequence folders
// with .pcd and KITTI velodyne clouds.
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

#include "io_files.hpp"
#include "test_support.hpp"

#if KNNOCC_HAVE_OCTOMAP
#include <octomap/ScanGraph.h>
#endif

using namespace knnocc::test::io_files;  // io, fs, Point3f, file helpers

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
