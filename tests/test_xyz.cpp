// ASCII x y z clouds (io/xyz.hpp), and OctoMap's scan.dat.

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

TEST_CASE("io.xyz parsing") {
  ScratchDir dir("xyz");
  const std::string p = dir.file("points.xyz");
  write_bytes(p,
              "# a comment line\n"
              "1 2 3\n"
              "\n"
              "   \t\n"
              "  # indented comment\n"
              "-0.0434742 -4.82982 0.499645\r\n"
              "4\t5\t6 255 128 0 any text at all\n"
              "+1e-3 2E2 -inf\n"
              "7 8 9");  // no final newline
  const io::Cloud c = io::read_xyz(p);
  REQUIRE(c.points.size() == 5);
  CHECK(c.ids.empty());
  CHECK(c.points[0].x == 1.0f);
  CHECK(c.points[1].x == -0.0434742f);
  CHECK(c.points[1].z == 0.499645f);
  CHECK(c.points[2].z == 6.0f);
  CHECK(c.points[3].x == 1e-3f);
  CHECK(c.points[3].y == 200.0f);
  CHECK(c.points[3].z == -std::numeric_limits<float>::infinity());
  CHECK(c.points[4].z == 9.0f);

  SUBCASE("a short line reports its line number") {
    const std::string bad = dir.file("bad.xyz");
    write_bytes(bad, "1 2 3\n# c\n4 5 6\n7 8\n");
    CHECK_THROWS_AS(io::read_xyz(bad), io::Error);
    const std::string msg = error_of([&] { io::read_xyz(bad); });
    CHECK(contains(msg, bad));
    CHECK(contains(msg, "line 4: expected 3 numbers (x y z), found 2"));
  }
  SUBCASE("an unparsable number reports its line number") {
    const std::string bad = dir.file("word.xyz");
    write_bytes(bad, "1 2 3\n1 two 3\n");
    const std::string msg = error_of([&] { io::read_xyz(bad); });
    CHECK(contains(msg, bad));
    CHECK(contains(msg, "line 2: cannot parse 'two' as a number"));
  }
  SUBCASE("empty file gives an empty cloud") {
    const std::string e = dir.file("empty.xyz");
    write_bytes(e, "");
    CHECK(io::read_xyz(e).points.empty());
  }
}

TEST_CASE("io.real data: OctoMap FR-079 scan.dat") {
  const std::string path = knnocc::test::scan_dat_path();  // decompressed by the ctest fixture
  if (path.empty()) {
    knnocc::test::skip("scan.dat not decompressed into the build tree; skipping");
    return;
  }
  const io::Cloud c = io::read_points(path);
  CHECK(c.points.size() == 88206);
  double min_range = 1e9;
  double max_range = 0.0;
  for (const Point3f& q : c.points) {
    const double r = std::sqrt(double(q.x) * q.x + double(q.y) * q.y + double(q.z) * q.z);
    min_range = std::min(min_range, r);
    max_range = std::max(max_range, r);
  }
  CHECK(min_range > 0.4);  // README: ranges 0.47-29.0 m
  CHECK(max_range < 29.5);
}
