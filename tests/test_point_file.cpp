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
