// read_points (io/point_file.hpp): a reader by extension.

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

TEST_CASE("io.read_points dispatches on the extension") {
  ScratchDir dir("point_file");
  const std::vector<Point3f> pts = {{1, 2, 3}, {4, 5, 6}};
  io::write_ply(dir.file("a.ply"), pts);
  for (const char* name : {"a.xyz", "a.dat", "a.txt", "A.XYZ"}) {
    write_bytes(dir.file(name), "1 2 3\n4 5 6\n");
  }
  for (const char* name : {"a.ply", "a.xyz", "a.dat", "a.txt", "A.XYZ"}) {
    CAPTURE(name);
    const io::Cloud c = io::read_points(dir.file(name));
    REQUIRE(c.points.size() == 2);
    CHECK(c.points[1].y == 5.0f);
  }
  const std::string bz = dir.file("scan.dat.bz2");
  write_bytes(bz, "BZh9");
  std::string msg = error_of([&] { io::read_points(bz); });
  CHECK(contains(msg, bz));
  CHECK(contains(msg, "compressed input: decompress first, e.g. bzip2 -dk FILE"));
  msg = error_of([&] { io::read_points(dir.file("cloud.las")); });
  CHECK(contains(msg, "unknown point-file extension '.las'"));
  CHECK(contains(error_of([&] { io::read_points(dir.file("noext")); }),
                 "unknown point-file extension"));
}

TEST_CASE(
    "point_file.ids are a property of the format: an empty cloud that declares them has ids") {
  ScratchDir dir("point_file_empty_ids");
  const std::string ply = dir.file("e.ply"), pcd = dir.file("e.pcd"), bare = dir.file("b.ply");
  write_bytes(ply,
              "ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty float x\n"
              "property float y\nproperty float z\nproperty uint id\nend_header\n");
  write_bytes(pcd,
              "FIELDS x y z id\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\nWIDTH 0\nHEIGHT 1\n"
              "POINTS 0\nDATA ascii\n");
  write_bytes(bare,
              "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
              "property float z\nend_header\n");
  for (const std::string& path : {ply, pcd}) {
    CAPTURE(path);
    const io::Cloud c = io::read_points(path);
    CHECK(c.points.empty());
    CHECK(c.has_ids());
  }
  CHECK_FALSE(io::read_points(bare).has_ids());
  // Written back, the empty cloud still declares them; cropped to nothing, it keeps them.
  io::write_ply_cloud(dir.file("copy.ply"), io::read_points(ply));
  CHECK(io::read_points(dir.file("copy.ply")).has_ids());
  io::Cloud c;
  c.points = {{1, 0, 0}};
  c.ids = {7};
  io::crop_cloud(c, 0.5);
  CHECK(c.points.empty());
  CHECK(c.has_ids());
}
