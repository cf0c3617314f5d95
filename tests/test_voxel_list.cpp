// Voxel lists (io/voxel_list.hpp): sorted, and read back.

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

TEST_CASE("io.voxel_list is sorted and round-trips") {
  ScratchDir dir("voxels");
  const std::string p = dir.file("map.txt");
  std::vector<io::VoxelRecord> v = {
      {0.5, -1.25, 2.0, 0.85f}, {-0.5, 3.0, 1.0, -2.0f},       {0.5, -1.25, -2.0, 1.5f},
      {0.5, -2.0, 9.0, 0.4f},   {0.0078125, 1e-7, -0.0, 3.5f},
  };
  io::write_voxel_list(p, v);
  CHECK_FALSE(knnocc::test::has_temporary_beside(p));
  CHECK(read_text(p) ==
        "-0.500000 3.000000 1.000000 -2.000000\n"
        "0.007812 0.000000 -0.000000 3.500000\n"
        "0.500000 -2.000000 9.000000 0.400000\n"
        "0.500000 -1.250000 -2.000000 1.500000\n"
        "0.500000 -1.250000 2.000000 0.850000\n");
  const std::vector<io::VoxelRecord> back = io::read_voxel_list(p);
  REQUIRE(back.size() == 5);
  CHECK(back[0].x == -0.5);
  CHECK(back[2].y == -2.0);
  CHECK(back[4].z == 2.0);
  CHECK(back[4].logodds == doctest::Approx(0.85f).epsilon(1e-6));

  // Random voxel centres survive within the 1e-6 print precision.
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> cell(-500, 500);
  std::vector<io::VoxelRecord> many;
  for (int i = 0; i < 2000; ++i) {
    many.push_back({(cell(rng) + 0.5) * 0.05, (cell(rng) + 0.5) * 0.05, (cell(rng) + 0.5) * 0.05,
                    static_cast<float>(cell(rng)) / 100.0f});
  }
  io::write_voxel_list(p, many);
  const std::vector<io::VoxelRecord> many_back = io::read_voxel_list(p);
  REQUIRE(many_back.size() == many.size());
  for (std::size_t i = 1; i < many_back.size(); ++i) {
    const auto& a = many_back[i - 1];
    const auto& b = many_back[i];
    CHECK((a.x < b.x || (a.x == b.x && (a.y < b.y || (a.y == b.y && a.z <= b.z)))));
  }
  std::sort(many.begin(), many.end(), [](const io::VoxelRecord& a, const io::VoxelRecord& b) {
    return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
  });
  std::string expected;
  for (std::size_t i = 0; i < many.size(); ++i) {
    CHECK(std::abs(many_back[i].x - many[i].x) <= 1e-6);
    CHECK(std::abs(many_back[i].logodds - many[i].logodds) <= 1e-6f);
    char line[512];
    std::snprintf(line, sizeof line, "%.6f %.6f %.6f %.6f\n", many[i].x, many[i].y, many[i].z,
                  static_cast<double>(many[i].logodds));
    expected += line;
  }
  CHECK(read_text(p) == expected);  // byte-identical to printf("%.6f")

  // Values that stress the fast formatter: exact ties, -0, rounding carries, large magnitudes.
  const std::vector<double> tricky = {0.0,    -0.0,      2.5e-6,          -2.5e-6,
                                      1.5e-6, 0.0000005, 999999.9999995,  1234567.891,
                                      -1e300, 0.1,       -0.049999999999, 1.0 / 3.0};
  std::vector<io::VoxelRecord> tv;
  for (std::size_t i = 0; i < tricky.size(); ++i) tv.push_back({double(i), 0.0, tricky[i], 0.0f});
  io::write_voxel_list(p, tv);
  std::string tricky_expected;
  for (std::size_t i = 0; i < tricky.size(); ++i) {
    char line[512];
    std::snprintf(line, sizeof line, "%.6f %.6f %.6f %.6f\n", double(i), 0.0, tricky[i], 0.0);
    tricky_expected += line;
  }
  CHECK(read_text(p) == tricky_expected);

  CHECK(contains(error_of([&] {
                   io::write_voxel_list(dir.file("nan.txt"), {{std::nan(""), 0.0, 0.0, 1.0f}});
                 }),
                 "non-finite coordinate"));
  CHECK_FALSE(fs::exists(dir.file("nan.txt")));
  const std::string bad = dir.file("bad.txt");
  write_bytes(bad, "1 2 3 4\n1 2 3\n");
  const std::string msg = error_of([&] { io::read_voxel_list(bad); });
  CHECK(contains(msg, bad));
  CHECK(contains(msg, "line 2: expected 4 numbers"));
}
