// PLY clouds (io/ply.hpp): ascii and binary, both endians, extra properties and elements, ids,
// malformed files.

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

TEST_CASE("io.ply binary round trip") {
  ScratchDir dir("ply_roundtrip");
  const std::vector<Point3f> pts = sample_points();

  SUBCASE("without ids") {
    const std::string p = dir.file("cloud.ply");
    io::write_ply(p, pts);
    const io::Cloud c = io::read_ply(p);
    REQUIRE(c.points.size() == pts.size());
    CHECK(c.ids.empty());
    for (std::size_t i = 0; i < pts.size(); ++i) {
      CHECK(same_bits(c.points[i].x, pts[i].x));
      CHECK(same_bits(c.points[i].y, pts[i].y));
      CHECK(same_bits(c.points[i].z, pts[i].z));
    }
    CHECK(fs::file_size(p) == read_text(p).find("end_header\n") + 11 + 12 * pts.size());
    CHECK_FALSE(knnocc::test::has_temporary_beside(p));
  }
  SUBCASE("with ids") {
    std::vector<std::uint64_t> ids;
    for (std::size_t i = 0; i < pts.size(); ++i) ids.push_back(4000000000ull - i * 3);
    const std::string p = dir.file("cloud_ids.ply");
    io::write_ply(p, pts, &ids);
    CHECK(contains(read_text(p), "property uint id\n"));
    const io::Cloud c = io::read_ply(p);
    REQUIRE(c.points.size() == pts.size());
    CHECK(c.ids == ids);
    for (std::size_t i = 0; i < pts.size(); ++i) CHECK(same_bits(c.points[i].y, pts[i].y));
  }
  SUBCASE("ascii writer") {
    std::vector<std::uint64_t> ids(pts.size(), 17);
    const std::string p = dir.file("cloud_ascii.ply");
    io::write_ply(p, pts, &ids, /*binary=*/false);
    CHECK(contains(read_text(p), "format ascii 1.0\n"));
    const io::Cloud c = io::read_ply(p);
    REQUIRE(c.points.size() == pts.size());
    CHECK(c.ids == ids);
    for (std::size_t i = 0; i < pts.size(); ++i) CHECK(same_bits(c.points[i].z, pts[i].z));
  }
  SUBCASE("empty cloud") {
    const std::string p = dir.file("empty.ply");
    io::write_ply(p, {});
    CHECK(io::read_ply(p).points.empty());
  }
  SUBCASE("non-finite values survive") {
    const float inf = std::numeric_limits<float>::infinity();
    const std::vector<Point3f> odd = {{std::nanf(""), inf, -inf}, {1.0f, 2.0f, 3.0f}};
    const std::string p = dir.file("odd.ply");
    io::write_ply(p, odd);
    const io::Cloud c = io::read_ply(p);
    REQUIRE(c.points.size() == 2);
    CHECK(std::isnan(c.points[0].x));
    CHECK(c.points[0].y == inf);
    CHECK(c.points[0].z == -inf);
    CHECK(c.points[1].z == 3.0f);
  }
  SUBCASE("writer errors") {
    std::vector<std::uint64_t> short_ids(3, 1);
    const std::string p = dir.file("bad.ply");
    CHECK_THROWS_AS(io::write_ply(p, pts, &short_ids), io::Error);
    std::vector<std::uint64_t> big_ids(pts.size(), 1ull << 40);
    CHECK(contains(error_of([&] { io::write_ply(p, pts, &big_ids); }), "does not fit"));
    CHECK_FALSE(fs::exists(p));

    const std::string missing = dir.file("no/such/dir/x.ply");
    const std::string msg = error_of([&] { io::write_ply(missing, pts); });
    CHECK(contains(msg, missing));
    CHECK(contains(msg, "cannot create temporary file"));
  }
  SUBCASE("overwrite replaces atomically") {
    const std::string p = dir.file("over.ply");
    io::write_ply(p, pts);
    io::write_ply(p, {Point3f{1, 2, 3}});
    CHECK(io::read_ply(p).points.size() == 1);
    CHECK_FALSE(knnocc::test::has_temporary_beside(p));
  }
}

TEST_CASE("io.ply SLAM counters written back with ids and colours, binary and ascii") {
  ScratchDir dir("ply_counters");
  io::Cloud cloud;
  cloud.points = sample_points();
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    const auto n = static_cast<std::uint32_t>(i);
    cloud.ids.push_back(i + 5);
    cloud.colors.push_back({static_cast<std::uint8_t>(i), 7, 9});
    cloud.evidence.push_back({n, n + 3, i % 2 ? 0xFFFFFFFFu : n / 2});
  }
  for (const bool binary : {true, false}) {
    CAPTURE(binary);
    const std::string p = dir.file(binary ? "c.ply" : "c_ascii.ply");
    io::write_ply_cloud(p, cloud, binary);
    const io::Cloud c = io::read_ply(p);
    REQUIRE(c.evidence.size() == cloud.points.size());
    for (std::size_t i = 0; i < c.evidence.size(); ++i) {
      CHECK(c.evidence[i].found == cloud.evidence[i].found);
      CHECK(c.evidence[i].visible == cloud.evidence[i].visible);
      CHECK(c.evidence[i].observations == cloud.evidence[i].observations);
    }
    CHECK(c.ids == cloud.ids);
    CHECK(c.colors == cloud.colors);
  }
  io::Cloud short_counters = cloud;
  short_counters.evidence.pop_back();
  CHECK(contains(error_of([&] { io::write_ply_cloud(dir.file("s.ply"), short_counters); }),
                 "SLAM counters for"));
}

TEST_CASE("io.ply colours: uchar red green blue read and written") {
  ScratchDir dir("ply_colours");
  io::Cloud cloud;
  cloud.points = sample_points();
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    cloud.colors.push_back({static_cast<std::uint8_t>(i), static_cast<std::uint8_t>(255 - i % 256),
                            static_cast<std::uint8_t>(i * 7)});
    cloud.ids.push_back(i * 3);
  }
  for (const bool binary : {true, false}) {
    CAPTURE(binary);
    const std::string p = dir.file(binary ? "rgb.ply" : "rgb_ascii.ply");
    io::write_ply_cloud(p, cloud, binary);
    CHECK(contains(read_text(p),
                   "property uint id\nproperty uchar red\nproperty uchar green\n"
                   "property uchar blue\n"));
    const io::Cloud c = io::read_ply(p);
    REQUIRE(c.points.size() == cloud.points.size());
    CHECK(c.ids == cloud.ids);
    CHECK(c.colors == cloud.colors);
    for (std::size_t i = 0; i < c.points.size(); ++i)
      CHECK(same_bits(c.points[i].y, cloud.points[i].y));
  }
  // Colours between other properties, in an ascii file with an extra float.
  const std::string mixed = dir.file("mixed.ply");
  write_bytes(mixed,
              "ply\nformat ascii 1.0\nelement vertex 2\nproperty uchar blue\nproperty float x\n"
              "property uchar green\nproperty float y\nproperty float z\nproperty float nx\n"
              "property uchar red\nend_header\n3 1 2 1 1 0.5 1\n255 2 0 2 2 0.5 128\n");
  const io::Cloud m = io::read_ply(mixed);
  CHECK(m.colors == std::vector<knnocc::Rgb>{{1, 2, 3}, {128, 0, 255}});
  // Only two channels: no colours (the points are still read).
  const std::string two = dir.file("two_channels.ply");
  write_bytes(
      two,
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
      "property float z\nproperty uchar red\nproperty uchar green\nend_header\n1 2 3 4 5\n");
  CHECK(io::read_ply(two).colors.empty());
  // An ascii colour out of 0..255 is an error naming the file.
  const std::string bad = dir.file("bad_rgb.ply");
  write_bytes(bad,
              "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
              "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
              "end_header\n1 2 3 4 256 6\n");
  const std::string msg = error_of([&] { io::read_ply(bad); });
  CHECK(contains(msg, bad));
  CHECK(contains(msg, "as a colour"));
  // The writer checks the count.
  io::Cloud short_colors = cloud;
  short_colors.colors.pop_back();
  CHECK(contains(error_of([&] { io::write_ply_cloud(dir.file("short.ply"), short_colors); }),
                 "colours for"));
}

namespace {

// A one-channel-type colour test: `values` (as text, one vertex each) of PLY type `type` for red,
// green and blue, written ascii, binary little- and big-endian; returns the red channels read.
template <class T>
std::vector<std::vector<std::uint8_t>> colour_channels(ScratchDir& dir, const std::string& type,
                                                       const std::vector<T>& values) {
  std::vector<std::vector<std::uint8_t>> out;
  for (const char* format : {"ascii", "binary_little_endian", "binary_big_endian"}) {
    const bool big = std::string(format) == "binary_big_endian";
    std::string bytes = "ply\nformat " + std::string(format) + " 1.0\nelement vertex " +
                        std::to_string(values.size()) +
                        "\nproperty float x\nproperty float y\nproperty float z\nproperty " + type +
                        " red\nproperty " + type + " green\nproperty " + type +
                        " blue\nend_header\n";
    for (const T v : values) {
      if (std::string(format) == "ascii") {
        std::ostringstream line;
        line.precision(17);
        line << "1 2 3 " << +v << ' ' << +v << ' ' << +v << '\n';
        bytes += line.str();
      } else {
        for (const float c : {1.0f, 2.0f, 3.0f}) put(bytes, c, big);
        for (int k = 0; k < 3; ++k) put(bytes, v, big);
      }
    }
    const std::string p = dir.file(type + "_" + format + ".ply");
    write_bytes(p, bytes);
    const io::Cloud c = io::read_ply(p);
    REQUIRE(c.colors.size() == values.size());
    std::vector<std::uint8_t> red;
    for (const knnocc::Rgb& rgb : c.colors) {
      CHECK(rgb.g == rgb.r);
      CHECK(rgb.b == rgb.r);
      red.push_back(rgb.r);
    }
    out.push_back(red);
  }
  return out;
}

using Bytes = std::vector<std::uint8_t>;

}  // namespace

TEST_CASE("io.ply colours of every type scaled to 0..255, ascii and both endians") {
  ScratchDir dir("ply_colour_types");
  const auto same = [](const std::vector<Bytes>& got, const Bytes& want) {
    for (const Bytes& g : got) CHECK(g == want);
  };
  // uchar as is; ushort on the 16-bit scale (x 255/65535, rounded).
  same(colour_channels<std::uint8_t>(dir, "uchar", {0, 1, 128, 255}), {0, 1, 128, 255});
  same(colour_channels<std::uint8_t>(dir, "uint8", {7, 200}), {7, 200});
  same(colour_channels<std::uint16_t>(dir, "ushort", {0, 128, 129, 257, 32896, 65535}),
       {0, 0, 1, 1, 128, 255});
  same(colour_channels<std::uint16_t>(dir, "uint16", {65535, 0}), {255, 0});
  // Other integer types on the 0..255 scale: negative 0, above 255 clamped to 255.
  same(colour_channels<std::int8_t>(dir, "char", {-128, -1, 0, 77, 127}), {0, 0, 0, 77, 127});
  same(colour_channels<std::int16_t>(dir, "short", {-5, 0, 200, 255, 256, 32767}),
       {0, 0, 200, 255, 255, 255});
  same(colour_channels<std::int32_t>(dir, "int", {-70000, 3, 255, 70000}), {0, 3, 255, 255});
  same(colour_channels<std::uint32_t>(dir, "uint", {0, 254, 4294967295u}), {0, 254, 255});
  // float and double on 0..1, rounded; beyond it clamped, NaN 0.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  same(colour_channels<float>(dir, "float", {0.0f, 0.5f, 1.0f / 255, 0.998f, 1.0f, 1.5f, -0.2f}),
       {0, 128, 1, 254, 255, 255, 0});
  same(colour_channels<double>(dir, "double", {0.25, 1.0, 2.0, -1.0}), {64, 255, 255, 0});
  const std::vector<Bytes> with_nan = colour_channels<float>(dir, "float32", {nan, 0.2f});
  for (const Bytes& b : with_nan) CHECK(b == Bytes{0, 51});
}

TEST_CASE("io.ply colours of mixed types, and ascii tokens that are no value of their type") {
  ScratchDir dir("ply_colour_mixed");
  const std::string mixed = dir.file("mixed_types.ply");
  write_bytes(mixed,
              "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
              "property float z\nproperty float red\nproperty ushort green\nproperty int "
              "blue\nend_header\n1 2 3 0.2 65535 9\n");
  CHECK(io::read_ply(mixed).colors == std::vector<knnocc::Rgb>{{51, 255, 9}});
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
      "property float z\n";
  for (const auto& [type_name, token_text] :
       std::vector<std::pair<std::string, std::string>>{{"uchar", "256"},
                                                        {"char", "128"},
                                                        {"ushort", "-1"},
                                                        {"ushort", "65536"},
                                                        {"short", "40000"},
                                                        {"int", "1.5"},
                                                        {"float", "red"}}) {
    // Plain variables: doctest's CAPTURE is a lambda, which cannot capture a structured binding
    // in C++17 (clang refuses it).
    const std::string type = type_name, token = token_text;
    CAPTURE(type);
    CAPTURE(token);
    const std::string p = dir.file("bad_" + type + ".ply");
    write_bytes(p, head + "property " + type + " red\nproperty " + type + " green\nproperty " +
                       type + " blue\nend_header\n1 2 3 1 " + token + " 1\n");
    const std::string msg = error_of([&] { io::read_ply(p); });
    CHECK(contains(msg, p));
    CHECK(contains(msg, "as a colour of type"));
  }
}

TEST_CASE("io.ply ascii with extra properties, comments, CRLF header and a face element") {
  ScratchDir dir("ply_ascii");
  const std::string p = dir.file("ascii.ply");
  write_bytes(p,
              "ply\r\n"
              "format ascii 1.0\r\n"
              "comment made by hand\r\n"
              "obj_info anything at all\r\n"
              "element vertex 3\r\n"
              "property double x\r\n"
              "property uchar red\r\n"
              "property double y\r\n"
              "property uchar green\r\n"
              "property uchar blue\r\n"
              "property float64 z\r\n"
              "property float intensity\r\n"
              "property int32 id\r\n"
              "element face 2\r\n"
              "property list uchar int vertex_indices\r\n"
              "end_header\r\n"
              "1.5 255 -2.25 0 7 1e2 0.5 42\r\n"
              "  +3\t1 4 2 3 -0.125 9 7\n"
              "nan 0 inf 0 0 -inf 1 0\n"
              "3 0 1 2\n"
              "3 0 2 1\n");
  const io::Cloud c = io::read_ply(p);
  REQUIRE(c.points.size() == 3);
  CHECK(c.points[0].x == 1.5f);
  CHECK(c.points[0].y == -2.25f);
  CHECK(c.points[0].z == 100.0f);
  CHECK(c.points[1].x == 3.0f);
  CHECK(c.points[1].y == 4.0f);
  CHECK(c.points[1].z == -0.125f);
  // NaN/Inf are data, not errors: the mapping layer skips them.
  CHECK(std::isnan(c.points[2].x));
  CHECK(std::isinf(c.points[2].y));
  CHECK(c.points[2].z == -std::numeric_limits<float>::infinity());
  CHECK(c.ids == std::vector<std::uint64_t>{42, 7, 0});
}

TEST_CASE("io.ply ascii element before vertex is skipped") {
  ScratchDir dir("ply_ascii_before");
  const std::string p = dir.file("before.ply");
  write_bytes(p,
              "ply\nformat ascii 1.0\n"
              "element face 2\nproperty list uchar int vertex_indices\nproperty uchar flag\n"
              "element vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
              "end_header\n"
              "3 0 1 2 1\n4 0 1 2 3 0\n"
              "1 2 3\n4 5 6\n");
  const io::Cloud c = io::read_ply(p);
  REQUIRE(c.points.size() == 2);
  CHECK(c.points[1].x == 4.0f);
  CHECK(c.points[1].z == 6.0f);
}

TEST_CASE("io.ply big-endian hand-crafted bytes") {
  ScratchDir dir("ply_be");
  const std::string p = dir.file("be.ply");
  std::string bytes =
      "ply\n"
      "format binary_big_endian 1.0\n"
      "element vertex 2\n"
      "property float x\n"
      "property float y\n"
      "property float z\n"
      "property ushort id\n"
      "property uchar red\n"
      "element face 1\n"
      "property list uchar int vertex_indices\n"
      "end_header\n";
  // Vertex 0 spelled out byte by byte: 1.0f, -3.5f, 2.0f, id 258, red 9.
  const unsigned char v0[] = {0x3F, 0x80, 0x00, 0x00, 0xC0, 0x60, 0x00, 0x00,
                              0x40, 0x00, 0x00, 0x00, 0x01, 0x02, 0x09};
  bytes.append(reinterpret_cast<const char*>(v0), sizeof v0);
  put(bytes, 0.25f, true);
  put(bytes, 1e6f, true);
  put(bytes, -7.0f, true);
  put(bytes, std::uint16_t{65535}, true);
  put(bytes, std::uint8_t{1}, true);
  put(bytes, std::uint8_t{3}, true);  // face: 3 indices
  for (int k = 0; k < 3; ++k) put(bytes, std::int32_t{k}, true);
  write_bytes(p, bytes);

  const io::Cloud c = io::read_ply(p);
  REQUIRE(c.points.size() == 2);
  CHECK(c.points[0].x == 1.0f);
  CHECK(c.points[0].y == -3.5f);
  CHECK(c.points[0].z == 2.0f);
  CHECK(c.points[1].x == 0.25f);
  CHECK(c.points[1].y == 1e6f);
  CHECK(c.points[1].z == -7.0f);
  CHECK(c.ids == std::vector<std::uint64_t>{258, 65535});
}

TEST_CASE("io.ply binary doubles, extra properties and a scalar element before vertex") {
  ScratchDir dir("ply_le_double");
  for (const bool big : {false, true}) {
    CAPTURE(big);
    const std::string p = dir.file(big ? "be_double.ply" : "le_double.ply");
    std::string bytes = std::string("ply\nformat ") +
                        (big ? "binary_big_endian" : "binary_little_endian") +
                        " 1.0\n"
                        "element camera 2\nproperty float32 fx\nproperty int16 w\n"
                        "element vertex 3\n"
                        "property uint8 red\nproperty uint8 green\nproperty uint8 blue\n"
                        "property float64 x\nproperty double y\nproperty float64 z\n"
                        "property float intensity\nproperty int8 id\n"
                        "element face 1\nproperty list uchar uint vertex_indices\n"
                        "end_header\n";
    for (int k = 0; k < 2; ++k) {
      put(bytes, 525.0f, big);
      put(bytes, std::int16_t{640}, big);
    }
    for (int i = 0; i < 3; ++i) {
      for (int k = 0; k < 3; ++k) put(bytes, std::uint8_t{200}, big);
      put(bytes, 0.1 * i, big);
      put(bytes, -1.0 - i, big);
      put(bytes, 1e300, big);  // beyond float range: becomes +inf, not UB
      put(bytes, 0.75f, big);
      put(bytes, std::int8_t{static_cast<std::int8_t>(100 + i)}, big);
    }
    put(bytes, std::uint8_t{2}, big);
    put(bytes, std::uint32_t{0}, big);
    put(bytes, std::uint32_t{1}, big);
    write_bytes(p, bytes);

    const io::Cloud c = io::read_ply(p);
    REQUIRE(c.points.size() == 3);
    CHECK(c.points[2].x == static_cast<float>(0.2));
    CHECK(c.points[1].y == -2.0f);
    CHECK(c.points[0].z == std::numeric_limits<float>::infinity());
    CHECK(c.ids == std::vector<std::uint64_t>{100, 101, 102});
  }
}

TEST_CASE("io.ply malformed files throw io::Error naming the file") {
  ScratchDir dir("ply_bad");
  const std::string xyz_props = "property float x\nproperty float y\nproperty float z\n";

  SUBCASE("cannot open") {
    const std::string p = dir.file("missing.ply");
    CHECK_THROWS_AS(io::read_ply(p), io::Error);
    const std::string msg = error_of([&] { io::read_ply(p); });
    CHECK(contains(msg, p));
    CHECK(contains(msg, "cannot open"));
    const std::string d = dir.file("");
    CHECK(contains(error_of([&] { io::read_ply(d); }), "not a regular file"));
  }
  SUBCASE("not a PLY") {
    check_ply_error(dir, "notply.ply", "hello\nformat ascii 1.0\n", "not a PLY");
    check_ply_error(dir, "plyx.ply", "plyx\n", "not a PLY");
    check_ply_error(dir, "empty.ply", "", "not a PLY");
  }
  SUBCASE("format problems") {
    check_ply_error(dir, "noformat.ply", "ply\nelement vertex 0\n" + xyz_props + "end_header\n",
                    "no format line");
    check_ply_error(
        dir, "badformat.ply",
        "ply\nformat binary_middle_endian 1.0\nelement vertex 0\n" + xyz_props + "end_header\n",
        "unknown PLY format 'binary_middle_endian'");
    check_ply_error(dir, "noend.ply", "ply\nformat ascii 1.0\nelement vertex 0\n" + xyz_props,
                    "no end_header");
    check_ply_error(dir, "keyword.ply", "ply\nformat ascii 1.0\nelemnt vertex 0\nend_header\n",
                    "unknown PLY header keyword 'elemnt'");
    check_ply_error(dir, "badtype.ply",
                    "ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\nend_header\n",
                    "unknown PLY property type 'float128'");
    check_ply_error(dir, "badcount.ply",
                    "ply\nformat ascii 1.0\nelement vertex -5\n" + xyz_props + "end_header\n",
                    "invalid element count '-5'");
  }
  SUBCASE("vertex layout problems") {
    check_ply_error(dir, "novertex.ply", "ply\nformat ascii 1.0\nend_header\n",
                    "no 'vertex' element");
    check_ply_error(dir, "noy.ply",
                    "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                    "property float z\nend_header\n1 2\n",
                    "no property 'y'");
    check_ply_error(dir, "intx.ply",
                    "ply\nformat ascii 1.0\nelement vertex 1\nproperty int x\n"
                    "property float y\nproperty float z\nend_header\n1 2 3\n",
                    "'x' must be a float or double");
    check_ply_error(dir, "floatid.ply",
                    "ply\nformat ascii 1.0\nelement vertex 1\n" + xyz_props +
                        "property float id\nend_header\n1 2 3 4\n",
                    "'id' must be an integer");
  }
  SUBCASE("absurd vertex counts never allocate") {
    std::string bin = "ply\nformat binary_little_endian 1.0\nelement vertex 2000000000\n" +
                      xyz_props + "end_header\n";
    bin.append(100, '\0');  // 100 bytes of data behind a header claiming 24 GB
    check_ply_error(dir, "huge.ply", bin,
                    "file truncated: header claims 2000000000 vertices but only 100 bytes of "
                    "data");
    check_ply_error(
        dir, "huge_ascii.ply",
        "ply\nformat ascii 1.0\nelement vertex 2000000000\n" + xyz_props + "end_header\n1 2 3\n",
        "file truncated: header claims 2000000000 vertices");
    check_ply_error(dir, "huge_before.ply",
                    "ply\nformat binary_little_endian 1.0\nelement junk 18446744073709551615\n"
                    "property double a\nelement vertex 1\n" +
                        xyz_props + "end_header\n",
                    "file truncated: element 'junk'");
  }
  SUBCASE("truncated binary") {
    std::string bin =
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\n" + xyz_props + "end_header\n";
    for (int k = 0; k < 8; ++k) put(bin, 1.0f, false);  // 2 2/3 vertices
    check_ply_error(dir, "short.ply", bin,
                    "file truncated: header claims 3 vertices but only 32 bytes of data");
  }
  SUBCASE("ascii data problems") {
    check_ply_error(dir, "short_ascii.ply",
                    "ply\nformat ascii 1.0\nelement vertex 3\n" + xyz_props +
                        "end_header\n1.000 2.000 3.000\n4.000 5.000 6.000\n",
                    "truncated ascii data: header claims 3 vertex records but data ends in "
                    "record 2");
    check_ply_error(
        dir, "word.ply",
        "ply\nformat ascii 1.0\nelement vertex 2\n" + xyz_props + "end_header\n1 2 3\n4.0 abc 6\n",
        "line 9 (vertex 1): cannot parse 'abc' as a number");
    check_ply_error(
        dir, "glued.ply",
        "ply\nformat ascii 1.0\nelement vertex 1\n" + xyz_props + "end_header\n1 2.5.1 3\n",
        "cannot parse '2.5.1'");
    check_ply_error(dir, "negid.ply",
                    "ply\nformat ascii 1.0\nelement vertex 1\n" + xyz_props +
                        "property int id\nend_header\n1 2 3 -4\n",
                    "negative id -4");
  }
  SUBCASE("binary list element before vertex is unsupported") {
    std::string bin =
        "ply\nformat binary_little_endian 1.0\nelement face 1\n"
        "property list uchar int vertex_indices\nelement vertex 1\n" +
        xyz_props + "end_header\n";
    bin.append(17, '\0');
    check_ply_error(dir, "facefirst.ply", bin, "unsupported binary PLY: element 'face'");
  }
}

// Header parsing is linear in the header's length and the header is bounded (1 MiB): crafted
// headers with many properties or elements are parsed or refused, never slowly.
TEST_CASE("io.ply long headers: many properties and elements parsed, past 1 MiB refused") {
  ScratchDir dir("ply_long_header");
  auto header_with = [](std::size_t props, std::size_t elements) {
    std::string h = "ply\nformat ascii 1.0\n";
    for (std::size_t e = 0; e < elements; ++e) h += "element e" + std::to_string(e) + " 0\n";
    h += "element vertex 2\nproperty float x\nproperty float y\nproperty float z\n";
    for (std::size_t i = 0; i < props; ++i) h += "property uchar p" + std::to_string(i) + "\n";
    return h + "end_header\n";
  };
  auto values = [](std::size_t props, const char* xyz) {
    std::string line = xyz;
    for (std::size_t i = 0; i < props; ++i) line += " 7";
    return line + "\n";
  };
  SUBCASE("30,000 extra properties") {
    const std::string p = dir.file("props.ply");
    write_bytes(p, header_with(30000, 0) + values(30000, "1 2 3") + values(30000, "4 5 6"));
    const io::Cloud c = io::read_ply(p);
    REQUIRE(c.points.size() == 2);
    CHECK(c.points[1].x == 4.0f);
    CHECK(c.points[1].z == 6.0f);
  }
  SUBCASE("30,000 empty elements before the vertices") {
    const std::string p = dir.file("elements.ply");
    write_bytes(p, header_with(0, 30000) + "1 2 3\n4 5 6\n");
    const io::Cloud c = io::read_ply(p);
    REQUIRE(c.points.size() == 2);
    CHECK(c.points[0].y == 2.0f);
  }
  SUBCASE("a duplicate found at the end of a long list") {
    const std::string p = dir.file("dup.ply");
    std::string h = header_with(30000, 0);
    h.insert(h.size() - 11, "property uchar p12345\n");
    write_bytes(p, h + "1 2 3\n");
    CHECK(error_of([&] { io::read_ply(p); }).find("duplicate property 'p12345'") !=
          std::string::npos);
  }
  SUBCASE("200,000 properties (a 4.5 MB header) are refused") {
    const std::string p = dir.file("huge.ply");
    write_bytes(p, header_with(200000, 0) + "1 2 3\n");
    const std::string e = error_of([&] { io::read_ply(p); });
    CHECK(e.find("huge.ply: PLY header is longer than 1 MiB") != std::string::npos);
  }
  SUBCASE("one endless header line is refused") {
    const std::string p = dir.file("line.ply");
    write_bytes(p, "ply\nformat ascii 1.0\ncomment " + std::string(2 << 20, 'c') + "\n");
    CHECK(error_of([&] { io::read_ply(p); }).find("header is longer than 1 MiB") !=
          std::string::npos);
  }
}

TEST_CASE("io.ply SLAM evidence: found, visible and observations read when present") {
  ScratchDir dir("ply_evidence");
  SUBCASE("ascii, some of the three, other properties between") {
    const std::string p = dir.file("ev.ply");
    write_bytes(p,
                "ply\nformat ascii 1.0\nelement vertex 2\n"
                "property float x\nproperty float y\nproperty float z\nproperty uint id\n"
                "property uchar red\nproperty ushort visible\nproperty int found\n"
                "end_header\n"
                "1 2 3 7 255 12 9\n"
                "4 5 6 8 0 3 0\n");
    const io::Cloud c = io::read_ply(p);
    REQUIRE(c.evidence.size() == 2);
    CHECK(c.evidence[0].found == 9);
    CHECK(c.evidence[0].visible == 12);
    CHECK(c.evidence[0].observations == 0);  // absent: 0, unknown
    CHECK(c.evidence[1].found == 0);
    CHECK(c.evidence[1].visible == 3);
    CHECK(c.evidence[0].has_ratio());
    CHECK(c.ids == std::vector<std::uint64_t>{7, 8});
  }
  SUBCASE("binary little and big endian, all three") {
    for (const char* fmt : {"binary_little_endian", "binary_big_endian"}) {
      CAPTURE(fmt);
      const bool big = std::string(fmt) == "binary_big_endian";
      std::string bytes = std::string("ply\nformat ") + fmt +
                          " 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                          "property float z\nproperty uint found\nproperty uint visible\n"
                          "property ushort observations\nend_header\n";
      auto put = [&](const void* v, std::size_t n) {
        std::string b(static_cast<const char*>(v), n);
        if (big) std::reverse(b.begin(), b.end());
        bytes += b;
      };
      const float xyz[3] = {1.0f, 2.0f, 3.0f};
      for (float f : xyz) put(&f, 4);
      const std::uint32_t found = 70000, visible = 90000;
      const std::uint16_t obs = 5;
      put(&found, 4);
      put(&visible, 4);
      put(&obs, 2);
      const std::string p = dir.file(std::string(fmt) + ".ply");
      write_bytes(p, bytes);
      const io::Cloud c = io::read_ply(p);
      REQUIRE(c.evidence.size() == 1);
      CHECK(c.evidence[0].found == 70000);
      CHECK(c.evidence[0].visible == 90000);
      CHECK(c.evidence[0].observations == 5);
      CHECK(c.points[0].z == 3.0f);
    }
  }
  SUBCASE("without them the cloud carries none") {
    const std::string p = dir.file("plain.ply");
    io::write_ply(p, {{1, 2, 3}});
    CHECK(io::read_ply(p).evidence.empty());
  }
  SUBCASE("kept by keyframe_to_world beside the points it keeps") {
    io::Cloud c;
    c.points = {{1, 0, 0}, {9, 0, 0}, {2, 0, 0}};
    c.ids = {1, 2, 3};
    c.evidence = {{1, 2, 3}, {4, 5, 6}, {7, 8, 9}};
    io::Pose pose;
    std::vector<knnocc::Point3d> w;
    std::vector<std::uint64_t> ids;
    std::vector<knnocc::PointEvidence> ev;
    io::keyframe_to_world(pose, c, 4.0, w, ids, &ev);
    REQUIRE(ev.size() == 2);
    CHECK(ev[0].found == 1);
    CHECK(ev[1].found == 7);
    CHECK(ids == std::vector<std::uint64_t>{1, 3});
  }
  SUBCASE("bad values are refused naming the file") {
    const std::string p = dir.file("neg.ply");
    write_bytes(p,
                "ply\nformat ascii 1.0\nelement vertex 1\n"
                "property float x\nproperty float y\nproperty float z\nproperty int found\n"
                "end_header\n1 2 3 -4\n");
    CHECK_THROWS_WITH_AS(io::read_ply(p), doctest::Contains("found -4"), io::Error);
    const std::string q = dir.file("real.ply");
    write_bytes(q,
                "ply\nformat ascii 1.0\nelement vertex 1\n"
                "property float x\nproperty float y\nproperty float z\nproperty float visible\n"
                "end_header\n1 2 3 4.5\n");
    CHECK_THROWS_WITH_AS(io::read_ply(q), doctest::Contains("'visible' must be an integer"),
                         io::Error);
  }
}
