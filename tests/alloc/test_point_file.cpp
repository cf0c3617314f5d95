// What reading a point file may allocate (io/point_file.hpp and the readers it dispatches to):
// a valid file costs its cloud (12 bytes a point, 8 an id) and at most twice that again while it
// grows, besides the file's bytes themselves (FileBuffer, outside operator new); a header that
// claims more than the file holds is refused before anything of that size is allocated.
#include <doctest/doctest.h>

#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <knnocc/io/kitti.hpp>
#include <knnocc/io/pcd.hpp>
#include <knnocc/io/ply.hpp>
#include <knnocc/io/point_file.hpp>
#include <knnocc/io/xyz.hpp>

#include "../test_support.hpp"
#include "counting_new.hpp"

namespace io = knnocc::io;
using knnocc::Point3f;

namespace {

std::string file(const std::string& name) { return knnocc::test::scratch_file("point_file", name); }

std::vector<Point3f> cloud(std::size_t n) {
  knnocc::test::Rng rng(11);
  std::uniform_real_distribution<float> u(-20.f, 20.f);
  std::vector<Point3f> pts(n);
  for (Point3f& p : pts) p = {u(rng), u(rng), u(rng)};
  return pts;
}

// Peak heap bytes held while reading `path`, beyond what was held before.
std::size_t peak_while_reading(const std::string& path, std::size_t& points) {
  const std::size_t before = knnocc::test::live_bytes();
  knnocc::test::reset_peak_live_bytes();
  {
    const io::Cloud c = io::read_points(path);
    points = c.points.size();
  }
  return knnocc::test::peak_live_bytes() - before;
}

}  // namespace

TEST_CASE("point_file.reading holds at most three times the cloud besides the file") {
  if (!knnocc::test::tracks_live_bytes()) {
    knnocc::test::skip("live heap bytes are measured with glibc's malloc_usable_size only");
    return;
  }
  const std::size_t n = 100000;
  const std::vector<Point3f> pts = cloud(n);
  std::vector<std::uint64_t> ids(n);
  for (std::size_t i = 0; i < n; ++i) ids[i] = i * 7;
  const std::vector<std::string> paths = {file("c.ply"),       file("c_ascii.ply"), file("c.pcd"),
                                          file("c_ascii.pcd"), file("c_lzf.pcd"),   file("c.bin"),
                                          file("c.xyz")};
  io::write_ply(paths[0], pts, &ids, true);
  io::write_ply(paths[1], pts, &ids, false);
  io::write_pcd(paths[2], pts, &ids, io::PcdData::binary);
  io::write_pcd(paths[3], pts, &ids, io::PcdData::ascii);
  io::write_pcd(paths[4], pts, &ids, io::PcdData::binary_compressed);
  io::write_kitti_bin(paths[5], pts);
  io::write_xyz(paths[6], pts);
  for (const std::string& p : paths) {
    CAPTURE(p);
    std::size_t points = 0;
    const std::size_t peak = peak_while_reading(p, points);
    CHECK(points == n);
    const std::size_t cloud_bytes = n * (sizeof(Point3f) + sizeof(std::uint64_t));
    INFO("peak heap " << peak << " bytes for a cloud of " << cloud_bytes);
    CHECK(peak <= 3 * cloud_bytes + (std::size_t{64} << 10));
  }
}

TEST_CASE("point_file.lying headers are refused without allocating what they claim") {
  auto refused = [](const std::string& name, const std::string& bytes) {
    CAPTURE(name);
    const std::string path = file(name);
    knnocc::test::write_file(path, bytes);
    knnocc::test::reset_largest_allocation();
    CHECK_THROWS_AS(io::read_points(path), io::Error);
    CHECK(knnocc::test::largest_allocation() < bytes.size() + 4096);
  };
  const std::string xyz3 = "property float x\nproperty float y\nproperty float z\n";
  refused("claims.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 2000000000\n" + xyz3 +
                            "end_header\n" + std::string(120, '\0'));
  refused("claims_ascii.ply",
          "ply\nformat ascii 1.0\nelement vertex 4000000000\n" + xyz3 + "end_header\n1 2 3\n");
  refused("claims_list.ply",
          "ply\nformat binary_little_endian 1.0\nelement face 3000000000\n"
          "property list uchar int vertex_indices\nelement vertex 1\n" +
              xyz3 + "end_header\n" + std::string(64, '\0'));
  refused("claims.pcd",
          "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
          "WIDTH 500000000\nHEIGHT 1\nPOINTS 500000000\nDATA binary\n" +
              std::string(120, '\0'));
  refused("odd.bin", std::string(17, '\0'));  // not a whole number of 16-byte points
}
