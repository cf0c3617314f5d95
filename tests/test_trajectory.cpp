// Poses (io/trajectory.hpp): TUM and KITTI lines, quaternion order, transforms.
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

TEST_CASE("io.poses parsing, quaternion order and transforms") {
  ScratchDir dir("poses");
  const double s = std::sqrt(0.5);
  const std::string p = dir.file("poses.txt");
  {
    std::ostringstream text;
    text.precision(17);
    text << "# stamp tx ty tz qx qy qz qw\n"
         << "10.5 1 2 3 0 0 0 1\n"
         << "\n"
         << "11.5 1 2 3 0 0 " << s << " " << s << "  # 90 deg about z\n"
         << "12.5 0 0 0 0 0 0 1.0005\n";  // slightly off: normalised
    write_bytes(p, text.str());
  }
  const std::vector<io::Pose> poses = io::read_poses(p);
  REQUIRE(poses.size() == 3);
  CHECK(poses[0].stamp == 10.5);
  CHECK(poses[0].t.isApprox(Eigen::Vector3d(1, 2, 3)));
  CHECK(poses[1].q.z() == doctest::Approx(s));
  CHECK(poses[1].q.w() == doctest::Approx(s));
  CHECK(poses[2].q.norm() == doctest::Approx(1.0).epsilon(1e-12));

  const Eigen::Vector3d moved = poses[1].transform() * Eigen::Vector3d(1, 0, 0);
  CHECK(moved.isApprox(Eigen::Vector3d(1, 3, 3), 1e-12));

  std::vector<Point3f> pts = {{1, 0, 0}, {0, 0, 5}};
  std::vector<Point3f> world;
  io::transform_to_world(poses[1], pts, world);
  REQUIRE(world.size() == 2);
  CHECK(world[0].x == doctest::Approx(1.0));
  CHECK(world[0].y == doctest::Approx(3.0));
  CHECK(world[1].z == doctest::Approx(8.0));
  io::transform_to_world(poses[1], pts, pts);  // in place is allowed
  CHECK(pts[1].z == doctest::Approx(8.0));

  const auto check_bad = [&](const std::string& name, const std::string& text,
                             const std::string& expect) {
    const std::string bad = dir.file(name);
    write_bytes(bad, text);
    CAPTURE(name);
    CHECK_THROWS_AS(io::read_poses(bad), io::Error);
    const std::string msg = error_of([&] { io::read_poses(bad); });
    CAPTURE(msg);
    CHECK(contains(msg, bad));
    CHECK(contains(msg, expect));
  };
  check_bad("norm.txt", "# h\n0 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 0.87\n",
            "line 3: quaternion norm 0.87 is not 1");
  check_bad("wxyz.txt", "0 0 0 0 1 0 0 0.5\n", "line 1: quaternion norm");
  check_bad("nan.txt", "0 0 0 0 0 0 0 1\n1 nan 0 0 0 0 0 1\n", "line 2: non-finite");
  check_bad("inf.txt", "inf 0 0 0 0 0 0 1\n", "line 1: non-finite");
  check_bad("short.txt", "0 0 0 0 0 0 1\n", "line 1: expected 8 numbers");
  check_bad("long.txt", "0 0 0 0 0 0 0 1 5\n", "line 1: expected 8 numbers");
  check_bad("word.txt", "0 0 0 zero 0 0 0 1\n", "line 1: cannot parse 'zero'");
}

TEST_CASE("trajectory.read_trajectory stops at the first pose beyond max_poses") {
  ScratchDir dir("trajectory_max");
  const std::string p = dir.file("after_000002.txt");
  // Three poses, then a fourth and 2 MB of poses after it: the read ends at line 5.
  std::string text = "# stamp tx ty tz qx qy qz qw\n0 0 0 0 0 0 0 1\n\n1 1 0 0 0 0 0 1\n";
  text += "2 2 0 0 0 0 0 1\n3 3 0 0 0 0 0 1\n";
  for (int i = 0; i < 100000; ++i) text += "4 4 0 0 0 0 0 1 # and more, unread\n";
  write_bytes(p, text);
  std::vector<std::size_t> lines;
  CHECK(io::read_trajectory(p).size() == 100004);
  const std::string msg = error_of([&] { io::read_trajectory(p, 3, &lines); });
  CHECK(contains(msg, p + ": line 6: more poses than the 3 expected"));
  write_bytes(p, text.substr(0, text.find("3 3")));
  const auto poses = io::read_trajectory(p, 3, &lines);
  REQUIRE(poses.size() == 3);
  CHECK(lines == std::vector<std::size_t>{2, 4, 5});
  CHECK(poses[2].t.x() == 2.0);
  // KITTI lines: stamp = row index, the limit the same.
  write_bytes(p, "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 1 0 1 0 0 0 0 1 0\n");
  CHECK(io::read_trajectory(p, 2).back().stamp == 1.0);
  CHECK(contains(error_of([&] { io::read_trajectory(p, 1); }), "line 2: more poses than the 1"));
  // A line of 2 MB (no newline): refused without holding the file, not read as one pose.
  write_bytes(p, "0 0 0 0 0 0 0 1\n" + std::string(2u << 20, '7'));
  CHECK(contains(error_of([&] { io::read_trajectory(p); }), "line 2 is longer than 1 MiB"));
  // Read piece by piece, the same poses as read whole (lines across the 1 MiB pieces, CRLF, BOM).
  std::string many = "\xEF\xBB\xBF";
  for (int i = 0; i < 60000; ++i)
    many += std::to_string(i) + " " + std::to_string(0.25 * i) + " 2 3 0 0 0 1\r\n";
  write_bytes(p, many);
  const auto whole = io::read_poses(p), pieces = io::read_trajectory(p);
  REQUIRE(pieces.size() == 60000);
  REQUIRE(whole.size() == 60000);
  for (std::size_t i = 0; i < whole.size(); i += 997) {
    CHECK(pieces[i].stamp == whole[i].stamp);
    CHECK(pieces[i].t == whole[i].t);
  }
}
