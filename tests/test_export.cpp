// Exports: the PNG writer (decoded here by an independent reader: bitwise CRC-32, stored
// deflate blocks, Adler-32), voxels as PLY points and cubes, and the tool's map picture.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <knnocc/io/ply.hpp>
#include <knnocc/io/png.hpp>
#include <knnocc/io/voxel_export.hpp>

#include "test_support.hpp"

namespace io = knnocc::io;
using knnocc::OccupancyMap;
using knnocc::OcKey;

using knnocc::test::read_file;

namespace {

std::string export_file(const std::string& name) {
  return knnocc::test::scratch_file("export", name);
}

std::uint32_t be32(const std::string& s, std::size_t at) {
  std::uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v = (v << 8) | static_cast<unsigned char>(s[at + i]);
  return v;
}

std::uint32_t crc32_bitwise(const std::string& s) {  // no table: a second implementation
  std::uint32_t crc = 0xFFFFFFFFu;
  for (const char ch : s) {
    crc ^= static_cast<unsigned char>(ch);
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

struct Decoded {
  std::uint32_t width = 0, height = 0;
  std::vector<std::uint8_t> rgb;
  std::size_t blocks = 0;
};

// Reads a PNG written with stored deflate blocks and checks every checksum on the way.
Decoded decode_png(const std::string& png) {
  Decoded d;
  REQUIRE(png.substr(0, 8) == std::string("\x89PNG\r\n\x1a\n", 8));
  std::string idat;
  std::size_t pos = 8;
  bool end = false;
  while (pos < png.size()) {
    const std::uint32_t n = be32(png, pos);
    const std::string type = png.substr(pos + 4, 4), data = png.substr(pos + 8, n);
    CHECK(crc32_bitwise(type + data) == be32(png, pos + 8 + n));
    if (type == "IHDR") {
      d.width = be32(data, 0);
      d.height = be32(data, 4);
      CHECK(data.substr(8) == std::string("\x08\x02\x00\x00\x00", 5));
    } else if (type == "IDAT") {
      idat += data;
    } else if (type == "IEND") {
      end = true;
    }
    pos += 12 + n;
  }
  CHECK(end);
  REQUIRE(idat.size() >= 6);
  CHECK((static_cast<unsigned char>(idat[0]) * 256 + static_cast<unsigned char>(idat[1])) % 31 ==
        0);  // zlib header check
  std::string raw;
  std::size_t p = 2;
  bool last = false;
  while (!last) {
    const auto hdr = static_cast<unsigned char>(idat[p]);
    REQUIRE((hdr & 6u) == 0);  // stored
    last = hdr & 1u;
    const unsigned len = static_cast<unsigned char>(idat[p + 1]) |
                         (static_cast<unsigned>(static_cast<unsigned char>(idat[p + 2])) << 8);
    const unsigned nlen = static_cast<unsigned char>(idat[p + 3]) |
                          (static_cast<unsigned>(static_cast<unsigned char>(idat[p + 4])) << 8);
    CHECK((len ^ 0xFFFFu) == nlen);
    raw += idat.substr(p + 5, len);
    p += 5 + len;
    ++d.blocks;
  }
  std::uint64_t a = 1, b = 0;
  for (const char c : raw) {
    a = (a + static_cast<unsigned char>(c)) % 65521;
    b = (b + a) % 65521;
  }
  CHECK(be32(idat, p) == ((b << 16) | a));
  CHECK(p + 4 == idat.size());
  const std::size_t row = std::size_t{d.width} * 3;
  REQUIRE(raw.size() == (row + 1) * d.height);
  for (std::uint32_t y = 0; y < d.height; ++y) {
    CHECK(raw[y * (row + 1)] == 0);  // filter: none
    d.rgb.insert(d.rgb.end(), raw.begin() + static_cast<std::ptrdiff_t>(y * (row + 1) + 1),
                 raw.begin() + static_cast<std::ptrdiff_t>((y + 1) * (row + 1)));
  }
  return d;
}

}  // namespace

TEST_CASE("png.written images decode to the same pixels") {
  knnocc::test::Rng rng(4);
  for (const auto& [w, h] : {std::pair<std::uint32_t, std::uint32_t>{1, 1}, {3, 2}, {257, 130}}) {
    std::vector<std::uint8_t> rgb(std::size_t{w} * h * 3);
    for (auto& v : rgb) v = static_cast<std::uint8_t>(rng());
    const std::string path = export_file("image.png");
    io::write_png(path, w, h, rgb);
    const Decoded d = decode_png(read_file(path));
    CHECK(d.width == w);
    CHECK(d.height == h);
    CHECK(d.rgb == rgb);
    if (w == 257) CHECK(d.blocks == 2);  // 130 rows of 772 bytes: more than one stored block
  }
  CHECK_THROWS_AS(io::encode_png(2, 2, std::vector<std::uint8_t>(11)), io::Error);
  CHECK_THROWS_AS(io::encode_png(0, 2, {}), io::Error);
  CHECK_THROWS_WITH_AS(io::write_png(export_file("bad.png"), 4, 4, {}),
                       doctest::Contains("bad.png"), io::Error);
}

TEST_CASE("voxel_export.points and cubes read back") {
  OccupancyMap<OcKey> map(0.2);
  const auto& p = map.params();
  map.set(OcKey(32768, 32768, 32768), p.clamp_max);  // centre (0.1, 0.1, 0.1)
  map.set(OcKey(32770, 32767, 32780), 0.5f);         // centre (0.5, -0.1, 2.5)
  map.set(OcKey(32771, 32767, 32780), -1.0f);        // free
  const std::string path = export_file("voxels.ply");
  for (const bool binary : {true, false}) {
    CAPTURE(binary);
    io::VoxelExportOptions o;
    o.binary = binary;
    CHECK(io::write_voxels_ply(path, map, o) == 2);
    const io::Cloud c = io::read_ply(path);
    REQUIRE(c.points.size() == 2);
    CHECK(c.points[0].x == doctest::Approx(0.1));
    CHECK(c.points[1].z == doctest::Approx(2.5));
    const std::string text = read_file(path);
    CHECK(text.find("property float logodds") != std::string::npos);
    o.which = io::VoxelSelection::all;
    CHECK(io::write_voxels_ply(path, map, o) == 3);
    CHECK(io::read_ply(path).points.size() == 3);

    o.shape = io::VoxelShape::cubes;
    o.which = io::VoxelSelection::occupied;
    CHECK(io::write_voxels_ply(path, map, o) == 2);
    const io::Cloud cubes = io::read_ply(path);  // vertices; the faces follow them
    REQUIRE(cubes.points.size() == 16);
    for (int k = 0; k < 8; ++k) {  // corners of the first voxel: 0 or 0.2 on each axis
      const auto& v = cubes.points[static_cast<std::size_t>(k)];
      CHECK(v.x == doctest::Approx((k & 1) ? 0.2 : 0.0));
      CHECK(v.y == doctest::Approx((k & 2) ? 0.2 : 0.0));
      CHECK(v.z == doctest::Approx((k & 4) ? 0.2 : 0.0));
    }
    const std::string mesh = read_file(path);
    CHECK(mesh.find("element face 12\nproperty list uchar int vertex_indices") !=
          std::string::npos);
    if (binary) {
      const std::size_t header = mesh.find("end_header\n") + 11;
      CHECK(mesh.size() == header + 16 * 15 + 12 * 17);  // xyz rgb; count + 4 ints
    } else {
      CHECK(mesh.find("\n4 8 10 11 9\n") != std::string::npos);  // the second cube's -z face
    }
  }
}

TEST_CASE("voxel_export.occupied voxels take their colour, the others height or grey") {
  OccupancyMap<OcKey> map(0.2);
  map.set(OcKey(32768, 32768, 32768), 1.0f);
  map.set(OcKey(32770, 32767, 32780), 0.5f);
  map.set(OcKey(32771, 32767, 32780), -1.0f);  // free: grey even with a colour
  const knnocc::VoxelColorOf<OcKey> color_of = [](const OcKey& k) -> std::optional<knnocc::Rgb> {
    if (k[0] == 32770) return std::nullopt;
    return knnocc::Rgb{12, 34, 56};
  };
  const std::string path = export_file("coloured.ply");
  io::VoxelExportOptions o;
  o.which = io::VoxelSelection::all;
  for (const bool binary : {true, false}) {
    o.binary = binary;
    REQUIRE(io::write_voxels_ply(path, map, o, color_of) == 3);
    const io::Cloud c = io::read_ply(path);  // sorted by key: the three voxels in x order
    REQUIRE(c.colors.size() == 3);
    CHECK(c.colors[0] == knnocc::Rgb{12, 34, 56});
    CHECK(c.colors[2] == knnocc::Rgb{200, 200, 200});
    REQUIRE(io::write_voxels_ply(path, map, o) == 3);  // without colours: by height
    const auto top = io::detail::height_colour(1.0);
    CHECK(io::read_ply(path).colors[1] == knnocc::Rgb{top[0], top[1], top[2]});
    REQUIRE(io::write_voxels_ply(path, map, o, color_of) == 3);
    CHECK(io::read_ply(path).colors[1] == knnocc::Rgb{top[0], top[1], top[2]});  // no colour
  }
}
