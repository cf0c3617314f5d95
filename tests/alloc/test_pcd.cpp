// PCD clouds (io/pcd.hpp): every encoding, ids and NaN, organised clouds, malformed files.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <knnocc/io/detail/lzf.hpp>
#include <knnocc/io/pcd.hpp>
#include <knnocc/io/point_file.hpp>

#include "../test_support.hpp"
#include "counting_new.hpp"

namespace io = knnocc::io;
using knnocc::Point3f;

using knnocc::test::append_le;
using knnocc::test::write_file;

namespace {

std::string pcd_file(const std::string& name) { return knnocc::test::scratch_file("pcd", name); }

bool same_point(const Point3f& a, const Point3f& b) {
  auto eq = [](float x, float y) { return (std::isnan(x) && std::isnan(y)) || x == y; };
  return eq(a.x, b.x) && eq(a.y, b.y) && eq(a.z, b.z);
}

void check_pcd_error(const std::string& name, const std::string& bytes, const std::string& needle) {
  CAPTURE(name);
  const std::string path = pcd_file(name);
  write_file(path, bytes);
  knnocc::test::reset_largest_allocation();
  try {
    (void)io::read_pcd(path);
    FAIL("no error");
  } catch (const io::Error& e) {
    // Nothing near what a lying header claims: at most the file and a few small vectors.
    const std::size_t largest = knnocc::test::largest_allocation();
    CHECK(largest < bytes.size() + 4096);
    CHECK(e.file() == path);
    CHECK_MESSAGE(e.problem().find(needle) != std::string::npos, e.problem());
  }
}

const std::string kXyzHeader =
    "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";

}  // namespace

TEST_CASE("pcd.round trip in every format, with ids and NaN") {
  knnocc::test::Rng rng(3);
  std::uniform_real_distribution<float> u(-50.f, 50.f);
  std::vector<Point3f> pts(5000);
  std::vector<std::uint64_t> ids(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    pts[i] = {u(rng), u(rng), std::round(u(rng))};
    ids[i] = 4000000000u - i * 7;
  }
  pts[17].x = std::nanf("");
  pts[18].z = -std::numeric_limits<float>::infinity();
  for (const io::PcdData data :
       {io::PcdData::ascii, io::PcdData::binary, io::PcdData::binary_compressed}) {
    for (const bool with_ids : {false, true}) {
      CAPTURE(static_cast<int>(data));
      CAPTURE(with_ids);
      const std::string path = pcd_file("round.pcd");
      io::write_pcd(path, pts, with_ids ? &ids : nullptr, data);
      io::PcdInfo info;
      knnocc::test::reset_largest_allocation();
      const io::Cloud back = io::read_pcd(path, &info);
      // The allocation counter of the malformed-file test does see real buffers.
      CHECK(knnocc::test::largest_allocation() >= pts.size() * sizeof(Point3f));
      CHECK(info.data == data);
      CHECK(info.points == pts.size());
      CHECK(info.width == pts.size());
      CHECK(info.height == 1);
      REQUIRE(back.points.size() == pts.size());
      std::size_t differing = 0;
      for (std::size_t i = 0; i < pts.size(); ++i) differing += !same_point(back.points[i], pts[i]);
      CHECK(differing == 0);
      CHECK(back.ids == (with_ids ? ids : std::vector<std::uint64_t>{}));
      // read_points dispatches .pcd here too.
      CHECK(io::read_points(path).points.size() == pts.size());
    }
  }
  const std::string empty = pcd_file("empty.pcd");
  for (const io::PcdData data :
       {io::PcdData::ascii, io::PcdData::binary, io::PcdData::binary_compressed}) {
    io::write_pcd(empty, {}, nullptr, data);
    CHECK(io::read_pcd(empty).points.empty());
  }
}

TEST_CASE("pcd.hand-built binary_compressed file with mixed fields") {
  // Two points; fields x (F4), rgb (U1 x3), y (F8), _ (2 bytes padding), z (F4), id (U2).
  // Stored field after field: x0 x1 | rgb0 rgb1 | y0 y1 | pad pad | z0 z1 | id0 id1.
  std::string raw;
  append_le(raw, 1.5f);
  append_le(raw, -2.25f);
  raw += "\x01\x02\x03\x04\x05\x06";
  append_le(raw, 10.0);
  append_le(raw, 1e300);  // narrows to +inf
  raw += std::string(4, '\x7f');
  append_le(raw, 0.0f);
  append_le(raw, 3.0f);
  append_le(raw, std::uint16_t{65535});
  append_le(raw, std::uint16_t{9});
  REQUIRE(raw.size() == 46);
  // LZF by hand: one literal run of 32 bytes, one of 16.
  std::string lzf;
  lzf += static_cast<char>(31);
  lzf += raw.substr(0, 32);
  lzf += static_cast<char>(13);
  lzf += raw.substr(32);
  std::string file =
      "VERSION .7\nFIELDS x rgb y _ z id\nSIZE 4 1 8 1 4 2\nTYPE F U F U F U\n"
      "COUNT 1 3 1 2 1 1\nWIDTH 1\nHEIGHT 2\nVIEWPOINT 1 2 3 0 1 0 0\nPOINTS 2\n"
      "DATA binary_compressed\n";
  append_le(file, static_cast<std::uint32_t>(lzf.size()));
  append_le(file, static_cast<std::uint32_t>(raw.size()));
  file += lzf;
  const std::string path = pcd_file("mixed.pcd");
  write_file(path, file);
  io::PcdInfo info;
  const io::Cloud c = io::read_pcd(path, &info);
  REQUIRE(c.points.size() == 2);
  CHECK(same_point(c.points[0], {1.5f, 10.0f, 0.0f}));
  CHECK(c.points[1].x == -2.25f);
  CHECK(std::isinf(c.points[1].y));
  CHECK(c.points[1].z == 3.0f);
  CHECK(c.ids == std::vector<std::uint64_t>{65535, 9});
  CHECK(info.height == 2);
  CHECK(info.viewpoint[0] == 1.0);
  CHECK(info.viewpoint[4] == 1.0);
  CHECK(info.fields == std::vector<std::string>{"x", "rgb", "y", "_", "z", "id"});

  // The same cloud as "binary": records packed point after point.
  std::string bin = file.substr(0, file.find("DATA")) + "DATA binary\n";
  for (int i = 0; i < 2; ++i) {
    bin += raw.substr(4 * i, 4);
    bin += raw.substr(8 + 3 * i, 3);
    bin += raw.substr(14 + 8 * i, 8);
    bin += raw.substr(30 + 2 * i, 2);
    bin += raw.substr(34 + 4 * i, 4);
    bin += raw.substr(42 + 2 * i, 2);
  }
  write_file(path, bin);
  const io::Cloud b = io::read_pcd(path);
  REQUIRE(b.points.size() == 2);
  CHECK(same_point(b.points[0], c.points[0]));
  CHECK(same_point(b.points[1], c.points[1]));
  CHECK(b.ids == c.ids);
}

TEST_CASE("pcd.binary_compressed is read straight into the cloud, equal to binary") {
  // 40,000 points; fields x (F4), rgb (U1 x3), y (F8), n (F4 x2), z (F4), id (U8): every value
  // is split between two decoded pieces somewhere, and the decoded data is larger than the cloud.
  const std::size_t n = 40000;
  knnocc::test::Rng rng(9);
  std::uniform_real_distribution<float> u(-20.f, 20.f);
  std::vector<Point3f> pts(n);
  std::vector<std::uint64_t> ids(n);
  for (std::size_t i = 0; i < n; ++i) {
    pts[i] = {u(rng), std::round(u(rng) * 10) / 10, u(rng)};
    ids[i] = (std::uint64_t{1} << 40) + i * 3;
  }
  std::string x, rgb, y, nrm, z, id, aos;
  for (std::size_t i = 0; i < n; ++i) {
    std::string rec;
    append_le(x, pts[i].x);
    append_le(rec, pts[i].x);
    const std::string color = {static_cast<char>(i), static_cast<char>(i >> 8), '\x7f'};
    rgb += color;
    rec += color;
    append_le(y, static_cast<double>(pts[i].y));
    append_le(rec, static_cast<double>(pts[i].y));
    for (int k = 0; k < 2; ++k) {
      append_le(nrm, 0.5f * static_cast<float>(k));
      append_le(rec, 0.5f * static_cast<float>(k));
    }
    append_le(z, pts[i].z);
    append_le(rec, pts[i].z);
    append_le(id, ids[i]);
    append_le(rec, ids[i]);
    aos += rec;
  }
  const std::string soa = x + rgb + y + nrm + z + id;
  REQUIRE(soa.size() == aos.size());
  const std::string head =
      "VERSION .7\nFIELDS x rgb y normal z id\nSIZE 4 1 8 4 4 8\nTYPE F U F F F U\n"
      "COUNT 1 3 1 2 1 1\nWIDTH 40000\nHEIGHT 1\nPOINTS 40000\n";
  const auto packed =
      io::detail::lzf_compress(reinterpret_cast<const unsigned char*>(soa.data()), soa.size());
  std::string compressed = head + "DATA binary_compressed\n";
  append_le(compressed, static_cast<std::uint32_t>(packed.size()));
  append_le(compressed, static_cast<std::uint32_t>(soa.size()));
  compressed.append(reinterpret_cast<const char*>(packed.data()), packed.size());
  const std::string cpath = pcd_file("mixed_many.pcd");
  write_file(cpath, compressed);
  write_file(pcd_file("mixed_many_binary.pcd"), head + "DATA binary\n" + aos);

  knnocc::test::reset_largest_allocation();
  const io::Cloud c = io::read_pcd(cpath);
  // The decoded fields (1.4 MB) are never held at once: the largest buffer is the file read in
  // or the cloud.
  REQUIRE(std::max(compressed.size(), n * sizeof(Point3f)) + 4096 < soa.size());
  CHECK(knnocc::test::largest_allocation() <=
        std::max(compressed.size(), n * sizeof(Point3f)) + 4096);
  const io::Cloud b = io::read_pcd(pcd_file("mixed_many_binary.pcd"));
  REQUIRE(c.points.size() == n);
  REQUIRE(b.points.size() == n);
  std::size_t differing = 0;
  for (std::size_t i = 0; i < n; ++i) {
    differing += !same_point(c.points[i], pts[i]) || !same_point(b.points[i], pts[i]);
  }
  CHECK(differing == 0);
  CHECK(c.ids == ids);
  CHECK(b.ids == ids);
}

TEST_CASE("pcd.rgb and rgba fields give colours in every encoding") {
  // PCL packs 0x00RRGGBB into the 4 bytes of "rgb" (TYPE F) and 0xAARRGGBB into "rgba" (TYPE U).
  const std::uint32_t packed[3] = {0x00102030u, 0xff00ff7fu, 0x80ffffffu};
  const std::vector<knnocc::Rgb> expect = {
      {0x10, 0x20, 0x30}, {0x00, 0xff, 0x7f}, {0xff, 0xff, 0xff}};
  for (const char* field : {"rgb F", "rgba U"}) {
    CAPTURE(field);
    const std::string name(field, std::strchr(field, ' '));
    const char type = field[name.size() + 1];
    const std::string header = "VERSION 0.7\nFIELDS x y z " + name + "\nSIZE 4 4 4 4\nTYPE F F F " +
                               type + "\nCOUNT 1 1 1 1\nWIDTH 3\nHEIGHT 1\nPOINTS 3\n";
    std::string rows, fields;  // point after point; field after field (binary_compressed)
    for (int i = 0; i < 3; ++i) {
      for (const float v : {1.0f * i, 2.0f, 3.0f}) append_le(rows, v);
      append_le(rows, packed[i]);
    }
    for (int f = 0; f < 4; ++f)
      for (int i = 0; i < 3; ++i)
        fields += rows.substr(16 * static_cast<std::size_t>(i) + 4 * f, 4);
    const std::vector<unsigned char> lzf = io::detail::lzf_compress(
        reinterpret_cast<const unsigned char*>(fields.data()), fields.size());
    std::string compressed = header + "DATA binary_compressed\n";
    append_le(compressed, static_cast<std::uint32_t>(lzf.size()));
    append_le(compressed, static_cast<std::uint32_t>(fields.size()));
    compressed.append(lzf.begin(), lzf.end());
    // Ascii: PCL >= 1.8 writes the packed value as an integer, older writers the float.
    std::string ascii = header + "DATA ascii\n0 2 3 " + std::to_string(packed[0]) + "\n1 2 3 " +
                        std::to_string(packed[1]) + "\n2 2 3 ";
    float as_float = 0.0f;
    std::memcpy(&as_float, &packed[2], 4);
    char text[64];
    std::snprintf(text, sizeof text, "%.9g\n", static_cast<double>(as_float));
    ascii += text;
    for (const std::string& file : {header + "DATA binary\n" + rows, compressed, ascii}) {
      const std::string path = pcd_file("colours.pcd");
      write_file(path, file);
      const io::Cloud c = io::read_pcd(path);
      REQUIRE(c.points.size() == 3);
      CHECK(c.points[2].x == 2.0f);
      CHECK(c.colors == expect);
    }
  }
  // rgb as three uchar values (COUNT 3) is not PCL's packed colour: skipped.
  const std::string path = pcd_file("rgb_count3.pcd");
  write_file(path,
             "FIELDS x y z rgb\nSIZE 4 4 4 1\nTYPE F F F U\nCOUNT 1 1 1 3\nWIDTH 1\nHEIGHT 1\n"
             "POINTS 1\nDATA ascii\n1 2 3 4 5 6\n");
  CHECK(io::read_pcd(path).colors.empty());
  // An ascii colour that is no number is an error naming the file.
  write_file(path, kXyzHeader.substr(0, kXyzHeader.find("FIELDS")) +
                       "FIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\nWIDTH 1\n"
                       "HEIGHT 1\nPOINTS 1\nDATA ascii\n1 2 3 red\n");
  try {
    (void)io::read_pcd(path);
    FAIL("no error");
  } catch (const io::Error& e) {
    CHECK(e.file() == path);
    CHECK_MESSAGE(e.problem().find("invalid colour") != std::string::npos, e.problem());
  }
}

TEST_CASE("pcd.ascii with extra fields, counts and an organised cloud") {
  const std::string path = pcd_file("ascii.pcd");
  write_file(path,
             "# comment\nFIELDS normal_x x y z rgb curvature\nSIZE 4 4 4 8 4 4\nTYPE F F F F F F\n"
             "COUNT 3 1 1 1 1 1\nWIDTH 2\nHEIGHT 2\nPOINTS 4\nDATA ascii\n"
             "0 0 1 1.5 2.5 3.5 4.2e6 0.1\n"
             "0 0 1 nan nan nan 0 0\r\n"
             "\n"
             "9 9 9 -1 -2 -3 0 0\n"
             "1 1 1 7 8 9 0 0");
  const io::Cloud c = io::read_pcd(path);
  REQUIRE(c.points.size() == 4);
  CHECK(same_point(c.points[0], {1.5f, 2.5f, 3.5f}));
  CHECK(std::isnan(c.points[1].x));
  CHECK(same_point(c.points[2], {-1.f, -2.f, -3.f}));
  CHECK(same_point(c.points[3], {7.f, 8.f, 9.f}));
  CHECK(c.ids.empty());
}

TEST_CASE("pcd.malformed files throw io::Error naming the file, without huge allocations") {
  const std::string ok_ascii =
      kXyzHeader + "WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n1 2 3\n4 5 6\n";
  check_pcd_error("notpcd.pcd", "ply\nformat ascii 1.0\n", "not a PCD file");
  check_pcd_error("empty.pcd", "", "empty file");
  check_pcd_error("nodata.pcd", kXyzHeader + "WIDTH 1\nHEIGHT 1\n", "no DATA line");
  check_pcd_error("baddata.pcd", kXyzHeader + "WIDTH 1\nHEIGHT 1\nDATA binary_lz4\n",
                  "unknown DATA type");
  check_pcd_error("nofields.pcd", "VERSION 0.7\nWIDTH 1\nHEIGHT 1\nDATA ascii\n1 2 3\n",
                  "no FIELDS line");
  check_pcd_error("sizes.pcd",
                  "FIELDS x y z\nSIZE 4 4\nTYPE F F F\nWIDTH 1\nHEIGHT 1\nDATA ascii\n1 2 3\n",
                  "SIZE has 2");
  check_pcd_error(
      "counts.pcd",
      "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1\nWIDTH 1\nHEIGHT 1\nDATA ascii\n",
      "COUNT has 2");
  check_pcd_error("type.pcd",
                  "FIELDS x y z\nSIZE 4 4 4\nTYPE F F D\nWIDTH 1\nHEIGHT 1\nDATA ascii\n",
                  "unknown TYPE 'D'");
  check_pcd_error("size3.pcd",
                  "FIELDS x y z\nSIZE 4 4 3\nTYPE F F F\nWIDTH 1\nHEIGHT 1\nDATA ascii\n",
                  "invalid SIZE '3'");
  check_pcd_error("intx.pcd",
                  "FIELDS x y z\nSIZE 4 4 4\nTYPE I F F\nWIDTH 1\nHEIGHT 1\nDATA ascii\n",
                  "'x' must be a float scalar");
  check_pcd_error("noz.pcd", "FIELDS x y\nSIZE 4 4\nTYPE F F\nWIDTH 1\nHEIGHT 1\nDATA ascii\n1 2\n",
                  "no field 'z'");
  check_pcd_error("points.pcd", kXyzHeader + "WIDTH 2\nHEIGHT 2\nPOINTS 3\nDATA ascii\n",
                  "!= POINTS 3");
  check_pcd_error("negative.pcd", kXyzHeader + "WIDTH -2\nHEIGHT 1\nDATA ascii\n",
                  "non-negative integer");
  check_pcd_error(
      "fewlines.pcd",
      kXyzHeader + "WIDTH 3\nHEIGHT 1\nPOINTS 3\nDATA ascii\n1.0 2.0 3.0\n4.0 5.0 6.0\n",
      "POINTS 3 but 2 data lines");
  check_pcd_error("manylines.pcd", ok_ascii + "7 8 9\n", "more data lines than POINTS");
  check_pcd_error("tokens.pcd", kXyzHeader + "WIDTH 1\nHEIGHT 1\nDATA ascii\n1.000 2.000\n",
                  "expected 3 values, found 2");
  check_pcd_error("word.pcd", kXyzHeader + "WIDTH 1\nHEIGHT 1\nDATA ascii\n1 two 3\n",
                  "line 10: cannot parse 'two'");
  // Absurd sizes behind tiny files: never believed.
  check_pcd_error("huge_ascii.pcd",
                  kXyzHeader + "WIDTH 4000000000\nHEIGHT 1000\nDATA ascii\n1 2 3\n",
                  "file truncated");
  std::string bin = kXyzHeader + "WIDTH 1000000000\nHEIGHT 1\nDATA binary\n";
  bin.append(30, '\0');
  check_pcd_error("huge_binary.pcd", bin, "file truncated: POINTS 1000000000");
  std::string comp = kXyzHeader + "WIDTH 300000000\nHEIGHT 1\nDATA binary_compressed\n";
  append_le(comp, std::uint32_t{2});
  append_le(comp, std::uint32_t{3600000000u});
  comp += std::string("\x00\x01", 2);
  check_pcd_error("huge_compressed.pcd", comp, "cannot hold the declared 3600000000 bytes");
  std::string lying = kXyzHeader + "WIDTH 1\nHEIGHT 1\nDATA binary_compressed\n";
  append_le(lying, std::uint32_t{1000});
  append_le(lying, std::uint32_t{12});
  lying += "abc";
  check_pcd_error("short_compressed.pcd", lying, "compressed block of 1000 bytes");
  std::string mismatch = kXyzHeader + "WIDTH 2\nHEIGHT 1\nDATA binary_compressed\n";
  append_le(mismatch, std::uint32_t{1});
  append_le(mismatch, std::uint32_t{12});
  mismatch += '\0';
  check_pcd_error("mismatch.pcd", mismatch, "POINTS 2 x 12 bytes per point differ");
  std::string corrupt = kXyzHeader + "WIDTH 1\nHEIGHT 1\nDATA binary_compressed\n";
  append_le(corrupt, std::uint32_t{3});
  append_le(corrupt, std::uint32_t{12});
  corrupt += std::string("\x00\x41\x20", 3);  // "A", then a reference 2 bytes back
  check_pcd_error("corrupt.pcd", corrupt, "corrupt binary_compressed data");
  check_pcd_error("nosizes.pcd", kXyzHeader + "WIDTH 1\nHEIGHT 1\nDATA binary_compressed\nab",
                  "no compressed-data sizes");
}

// Header parsing is linear and the header bounded (1 MiB): many fields are parsed, a 200,000
// field header is refused. A field costs a 72-byte record (and a 32-byte word while parsing) per
// at least 8 header bytes (its name, SIZE, TYPE and COUNT entries): at most 16 times the header.
TEST_CASE("pcd.long headers: 40,000 fields parsed, 200,000 refused") {
  auto header_with = [](std::size_t extra, const std::string& dup) {
    std::string fields = "FIELDS x y z", size = "SIZE 4 4 4", type = "TYPE F F F",
                count = "COUNT 1 1 1";
    for (std::size_t i = 0; i < extra; ++i) {
      fields += " f" + std::to_string(i);
      size += " 1";
      type += " U";
      count += " 1";
    }
    if (!dup.empty()) {
      fields += " " + dup;
      size += " 1";
      type += " U";
      count += " 1";
    }
    return "VERSION 0.7\n" + fields + "\n" + size + "\n" + type + "\n" + count +
           "\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA binary\n";
  };
  {
    std::string bytes = header_with(40000, "");
    const float xyz[3] = {1.5f, -2.f, 3.f};
    bytes.append(reinterpret_cast<const char*>(xyz), 12);
    bytes.append(40000, '\7');
    const std::string path = pcd_file("many_fields.pcd");
    write_file(path, bytes);
    knnocc::test::reset_largest_allocation();
    const io::Cloud c = io::read_pcd(path);
    REQUIRE(c.points.size() == 1);
    CHECK(c.points[0].x == 1.5f);
    CHECK(c.points[0].z == 3.f);
    CHECK(knnocc::test::largest_allocation() < 16 * bytes.size());
  }
  {
    const std::string path = pcd_file("dup_field.pcd");
    const std::string bytes = header_with(40000, "f39999");
    write_file(path, bytes);
    knnocc::test::reset_largest_allocation();
    CHECK_THROWS_WITH_AS(io::read_pcd(path), doctest::Contains("duplicate field f39999"),
                         io::Error);
    CHECK(knnocc::test::largest_allocation() < 16 * bytes.size());
  }
  check_pcd_error("huge_header.pcd", header_with(200000, ""), "PCD header is longer than 1 MiB");
}
