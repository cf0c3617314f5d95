// Map pictures: the robust extent (a far outlier does not shrink the map), the up axis (a map
// stored y-down draws like its z-up twin), the ceiling cut, and zlib-compressed files that
// decode to the rendered pixels.

#include <doctest/doctest.h>

#include <filesystem>

#include "test_support.hpp"

#ifdef KNNOCC_TEST_TOOL_HEADERS
#include "headless_chromium.hpp"  // decode_png_file
#include "map_picture.hpp"

using namespace knnocc;

namespace {

// Voxel (r, f, u) in display axes for `up`, stored in the map's own axes.
void put(OccupancyMap<OcKey>& map, cli::UpAxis up, int r, int f, int u, float v = 2.0f) {
  const cli::ViewFrame vf(up);
  int c[3];
  c[vf.axis[0]] = vf.sign[0] * r;
  c[vf.axis[1]] = vf.sign[1] * f;
  c[vf.axis[2]] = vf.sign[2] * u;
  OcKey k;
  REQUIRE(map.grid().coord_to_key(c[0] * 0.1 + 0.05, c[1] * 0.1 + 0.05, c[2] * 0.1 + 0.05, k));
  map.set(k, v);
}

// A room: floor, four walls, a ceiling at 2.5 m, a table; free air inside.
OccupancyMap<OcKey> room(cli::UpAxis up, bool ceiling) {
  OccupancyMap<OcKey> map(0.1);
  for (int r = 0; r < 40; ++r)
    for (int f = 0; f < 30; ++f) {
      put(map, up, r, f, 0);
      if (ceiling) put(map, up, r, f, 25);
      for (int u = 1; u < 25; ++u) {
        const bool wall = r == 0 || r == 39 || f == 0 || f == 29;
        const bool table = r >= 10 && r < 16 && f >= 10 && f < 14 && u < 8;
        put(map, up, r, f, u, wall || table ? 2.0f : -1.0f);
      }
    }
  return map;
}

}  // namespace

TEST_CASE("map_picture.robust extent, up axis and ceiling cut") {
  const cli::UpAxis z{2, 1}, minus_y{1, -1};
  OccupancyMap<OcKey> a = room(z, false);
  const cli::Image plain = cli::render_map_picture(a, z, "room");
  put(a, z, 2000, 0, 0);  // one wrong stereo match 200 m away
  const cli::Image with_outlier = cli::render_map_picture(a, z, "room");
  // 200 m at 0.1 m would be 2000 pixels; the extent grows only by its padding (and a note line).
  CHECK(with_outlier.width < plain.width * 11 / 10);
  CHECK(with_outlier.height < plain.height * 11 / 10);
  // The same room stored in ORB-SLAM's axes (y down) draws the same with up -y.
  OccupancyMap<OcKey> b = room(minus_y, false);
  put(b, minus_y, 2000, 0, 0);
  const cli::Image orb = cli::render_map_picture(b, minus_y, "room");
  CHECK(orb.width == with_outlier.width);
  CHECK(orb.height == with_outlier.height);
  std::size_t differ = 0;
  for (std::size_t i = 0; i < orb.rgb.size(); ++i) differ += orb.rgb[i] != with_outlier.rgb[i];
  // Only the axis names in the labels differ ("z up" / "-y up", "y up" / "z up").
  CHECK(differ < orb.rgb.size() / 200);
  // Without the cut the top view of a room with a ceiling would be the ceiling only.
  const OccupancyMap<OcKey> c = room(z, true);
  const cli::PictureFrame fr = cli::fit_picture_frame<OcKey>({&c}, z);
  CHECK(fr.ceiling_cut);
  CHECK(fr.cut > 8);    // above the table
  CHECK(fr.cut <= 25);  // at the ceiling
  const cli::PictureFrame no_ceiling = cli::fit_picture_frame<OcKey>({&a}, z);
  CHECK_FALSE(no_ceiling.ceiling_cut);
}

TEST_CASE("map_picture.compressed png decodes to the picture") {
  const cli::UpAxis z{2, 1};
  const OccupancyMap<OcKey> map = room(z, true);
  const std::string path =
      (std::filesystem::path(KNNOCC_BINARY_DIR) / "map_picture_test.png").string();
  cli::write_map_png(path, map, z, "room with ceiling");
  const cli::Image img = cli::render_map_picture(map, z, "room with ceiling");
  const test::RgbImage back = test::decode_png_file(path);
  CHECK(back.width == img.width);
  CHECK(back.height == img.height);
  CHECK(back.rgb == img.rgb);
  // Deflated: far smaller than the 3 bytes per pixel of stored blocks.
  CHECK(std::filesystem::file_size(path) * 10 < img.rgb.size());
  OccupancyMap<OcKey> empty(0.1);
  CHECK_THROWS_WITH_AS(cli::write_map_png(path + ".empty.png", empty, z, "x"),
                       doctest::Contains("empty.png"), io::Error);
}
#endif
