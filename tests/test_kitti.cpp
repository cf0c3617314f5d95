// KITTI velodyne scans, calibration and poses (io/kitti.hpp).
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
