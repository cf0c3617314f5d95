// VoxelColors (insertion/voxel_colors.hpp): the mean colour of the points that hit each voxel,
// against a brute force over the same points, with the scan inserter's hit rules.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <random>
#include <vector>

#include <knnocc/insertion/scan_inserter.hpp>
#include <knnocc/insertion/voxel_colors.hpp>

#include "test_support.hpp"

using knnocc::OccupancyMap;
using knnocc::OcKey;
using knnocc::Point3d;
using knnocc::Point3f;
using knnocc::Rgb;
using knnocc::VoxelColors;

TEST_CASE("voxel_colors.mean of the points in each voxel, as a brute force") {
  knnocc::test::Rng rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::uniform_int_distribution<int> c(0, 255);
  VoxelColors<> colors(0.25);
  std::map<std::uint64_t, std::array<double, 4>> sums;  // r g b n, by packed key
  for (int scan = 0; scan < 5; ++scan) {
    std::vector<Point3f> pts(2000);
    std::vector<Rgb> rgb(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) {
      pts[i] = {u(rng), u(rng), u(rng)};
      rgb[i] = {static_cast<std::uint8_t>(c(rng)), static_cast<std::uint8_t>(c(rng)),
                static_cast<std::uint8_t>(c(rng))};
      OcKey k;
      REQUIRE(colors.grid().point_to_key(pts[i], k));
      auto& s = sums[k.pack()];
      s[0] += rgb[i].r;
      s[1] += rgb[i].g;
      s[2] += rgb[i].b;
      s[3] += 1;
    }
    colors.add_scan(Point3d{0, 0, 0}, pts, rgb);
  }
  CHECK(colors.size() == sums.size());
  std::size_t wrong = 0;
  for (const auto& entry : sums) {
    const auto& s = entry.second;  // not a structured binding: lambdas capture it (clang 14)
    const auto m = colors.mean(OcKey::unpack(entry.first));
    REQUIRE(m);
    const auto expect = [&](int ch) { return static_cast<int>(std::floor(s[ch] / s[3] + 0.5)); };
    wrong += m->r != expect(0) || m->g != expect(1) || m->b != expect(2);
  }
  CHECK(wrong == 0);
  std::size_t visited = 0;
  colors.for_each([&](const OcKey& k, Rgb m) {
    ++visited;
    CHECK(colors.mean(k) == m);
  });
  CHECK(visited == sums.size());
  CHECK_FALSE(colors.mean(OcKey(1, 2, 3)));
  colors.clear();
  CHECK(colors.empty());
}

TEST_CASE("voxel_colors.the points that hit: the scan inserter's occupied voxels") {
  // Points beyond max range, non-finite points and points outside the key range colour nothing;
  // the voxels that get a colour are exactly those the inserter marks occupied.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<Point3f> pts = {{1.0f, 0, 0}, {2.9f, 0, 0},    {3.1f, 0, 0},
                              {nan, 0, 0},  {0, 2.0f, 0.5f}, {0, 0, -2.999f},
                              {1e7f, 0, 0}, {0, 0, 3.0f},    {0.5f, 0.5f, 0.5f}};
  std::vector<Rgb> rgb(pts.size(), Rgb{10, 20, 30});
  const Point3f origin{0.0f, 0.0f, 0.0f};
  VoxelColors<> colors(0.1);
  colors.add_scan(origin, pts, rgb, 3.0);
  OccupancyMap<OcKey> map(0.1);
  knnocc::ScanInserter<OcKey>(map).insert_point_cloud(origin, pts, 3.0, false);
  std::size_t occupied = 0;
  map.for_each_voxel([&](const OcKey& k, float v) {
    if (!map.is_occupied(v)) return;
    ++occupied;
    CHECK(colors.mean(k) == Rgb{10, 20, 30});
  });
  CHECK(occupied == 6);
  CHECK(colors.size() == occupied);
}
