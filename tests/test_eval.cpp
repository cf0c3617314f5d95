// Reference shapes and the Table 1 metrics against dense sampling and brute force.

#include <doctest/doctest.h>

#include <cmath>
#include <fstream>
#include <random>
#include <string>

#include <knnocc/eval/metrics.hpp>
#include <knnocc/eval/reference.hpp>
#include <knnocc/io/octomap_tree.hpp>

#include "test_support.hpp"

using namespace knnocc;
using eval::BoxRelation;

namespace {

eval::Reference tree_like() {
  eval::Reference ref;
  ref.has_ground = true;
  ref.ground_z = 0;
  ref.ellipsoids.push_back({{0.0, 0.0, 1.6}, {0.9, 0.8, 0.7}});
  ref.cuboids.push_back({{-0.27, -0.27, 0.0}, {0.27, 0.27, 0.77}});
  return ref;
}

bool inside_sampled(const eval::Reference& ref, const Point3d& p) {
  for (const auto& e : ref.ellipsoids) {
    const double x = (p.x - e.centre.x) / e.semi_axes.x, y = (p.y - e.centre.y) / e.semi_axes.y,
                 z = (p.z - e.centre.z) / e.semi_axes.z;
    if (x * x + y * y + z * z <= 1) return true;
  }
  for (const auto& c : ref.cuboids)
    if (p.x >= c.lo.x && p.x <= c.hi.x && p.y >= c.lo.y && p.y <= c.hi.y && p.z >= c.lo.z &&
        p.z <= c.hi.z)
      return true;
  return false;
}

}  // namespace

TEST_CASE("eval: box relation agrees with dense sampling of the box") {
  const eval::Reference ref = tree_like();
  test::Rng rng(3);
  std::uniform_real_distribution<double> u(-1.3, 1.3), uz(-0.2, 2.5), us(0.02, 0.3);
  std::size_t counts[3] = {0, 0, 0};
  for (int it = 0; it < 3000; ++it) {
    const Point3d lo{u(rng), u(rng), uz(rng)};
    const double s = us(rng);
    const Point3d hi{lo.x + s, lo.y + s, lo.z + s};
    std::size_t in = 0, total = 0;
    const int n = 8;  // 9^3 samples including the corners
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j <= n; ++j)
        for (int k = 0; k <= n; ++k, ++total)
          in += inside_sampled(ref, {lo.x + s * i / n, lo.y + s * j / n, lo.z + s * k / n});
    const BoxRelation rel = ref.relation(lo, hi);
    ++counts[static_cast<int>(rel)];
    if (in > 0 && in < total) CHECK(rel == BoxRelation::boundary);  // samples on both sides
    if (in == 0) CHECK(rel != BoxRelation::inside);
    // Convex solids: every corner inside one solid means the box is in it (inside or touching).
    if (in == total) CHECK(rel != BoxRelation::outside);
  }
  CHECK(counts[0] > 100);  // the random boxes cover all three cases
  CHECK(counts[1] > 100);
  CHECK(counts[2] > 100);
}

TEST_CASE("eval: distance to the solids agrees with dense sampling of their surfaces") {
  const eval::Reference ref = tree_like();
  // Surface samples of the ellipsoid (the cuboid's distance is elementary).
  std::vector<Point3d> surface;
  const auto& e = ref.ellipsoids[0];
  for (int i = 0; i <= 400; ++i)
    for (int j = 0; j < 800; ++j) {
      const double th = M_PI * i / 400, ph = 2 * M_PI * j / 800;
      surface.push_back({e.centre.x + e.semi_axes.x * std::sin(th) * std::cos(ph),
                         e.centre.y + e.semi_axes.y * std::sin(th) * std::sin(ph),
                         e.centre.z + e.semi_axes.z * std::cos(th)});
    }
  test::Rng rng(9);
  std::uniform_real_distribution<double> u(-2.0, 2.0), uz(1.0, 3.5);
  for (int it = 0; it < 60; ++it) {
    const Point3d p{u(rng), u(rng), uz(rng)};
    if (p.z < 1.2 && std::fabs(p.x) < 0.8 && std::fabs(p.y) < 0.8) continue;  // near the pot
    double best = INFINITY;
    for (const Point3d& q : surface)
      best = std::min(best, std::sqrt((p.x - q.x) * (p.x - q.x) + (p.y - q.y) * (p.y - q.y) +
                                      (p.z - q.z) * (p.z - q.z)));
    const double d = ref.distance(p);
    if (inside_sampled(ref, p)) {
      CHECK(d == 0.0);
    } else {
      CHECK(d <= best + 1e-9);   // exact distance is never above a sampled one
      CHECK(d >= best - 0.008);  // and the samples are 7 mm apart at most
    }
  }
  CHECK(ref.distance({0.27 + 0.5, 0.0, 0.3}) == doctest::Approx(0.5));  // cuboid face
}

TEST_CASE("eval: Table 1 metrics equal a brute-force count on a hand-made map") {
  const eval::Reference ref = tree_like();
  const double r = 0.1;
  OccupancyMap<OcKey> map(r);
  test::Rng rng(21);
  std::uniform_real_distribution<double> u(-1.6, 1.6), uz(-0.3, 2.6);
  for (int i = 0; i < 4000; ++i) {
    OcKey k;
    REQUIRE(map.grid().coord_to_key(u(rng), u(rng), uz(rng), k));
    map.set(k, (rng() % 3) ? 1.0f : -1.0f);
  }
  // Brute force: relation by dense sampling of each voxel, distance by the definition above.
  eval::Metrics want;
  map.for_each_voxel([&](const OcKey& k, float v) {
    const Point3d c{map.grid().index_to_coord(k[0]), map.grid().index_to_coord(k[1]),
                    map.grid().index_to_coord(k[2])};
    auto samples_inside = [&](double edge) {
      std::size_t in = 0;
      for (int i = 0; i <= 4; ++i)
        for (int j = 0; j <= 4; ++j)
          for (int l = 0; l <= 4; ++l)
            in += inside_sampled(ref, {c.x - edge / 2 + edge * i / 4, c.y - edge / 2 + edge * j / 4,
                                       c.z - edge / 2 + edge * l / 4});
      return in;
    };
    const std::size_t in = samples_inside(r), total = 125;
    const bool shell_like = in > 0 && in < total && c.z > 0;
    if (v < 0) {
      ++want.free;
      // Strictly inside: the voxel grown by a hair is still inside (the pot stands on z = 0,
      // a voxel border).
      want.free_inside += samples_inside(r + 1e-9) == total;
      return;
    }
    ++want.occupied;
    want.in_shell += shell_like;
    want.covered += shell_like || (in == total && c.z > 0);
    // On the ground: the voxel just above z = 0 (a voxel border), away from the solids.
    want.ground += std::fabs(c.z - r / 2) < 1e-9 && ref.distance(c) > 0.3;
    if (c.z < 0.3) return;
    ++want.evaluated;
    want.irrelevant += ref.distance(c) > 0.3;
  });
  const eval::Metrics got = eval::evaluate(map, ref);
  CHECK(got.occupied == want.occupied);
  CHECK(got.free == want.free);
  CHECK(got.evaluated == want.evaluated);
  CHECK(got.irrelevant == want.irrelevant);
  CHECK(got.free_inside == want.free_inside);
  CHECK(got.ground == want.ground);
  CHECK(want.ground > 20);
  // Sampling misses boxes that only graze a surface: the exact counts may be a few higher.
  CHECK(got.in_shell >= want.in_shell);
  CHECK(got.in_shell <= want.in_shell + want.in_shell / 20 + 2);
  CHECK(got.covered >= want.covered);
  CHECK(got.covered <= want.covered + want.covered / 20 + 2);
  CHECK(got.shell > 1000);
  CHECK(got.precision() == doctest::Approx(1.0 - double(want.irrelevant) / double(want.evaluated)));
}

TEST_CASE("eval: reference files round-trip; malformed ones name the file and line") {
  const auto dir = test::scratch_dir("eval");
  const std::string path = (dir / "ref.txt").string();
  eval::write_reference(path, tree_like());
  const eval::Reference back = eval::read_reference(path);
  CHECK(back.has_ground);
  REQUIRE(back.ellipsoids.size() == 1);
  REQUIRE(back.cuboids.size() == 1);
  CHECK(back.ellipsoids[0].semi_axes.y == 0.8);
  CHECK(back.cuboids[0].hi.z == 0.77);

  auto fails = [&](const std::string& text, const std::string& what) {
    const std::string bad = (dir / "bad.txt").string();
    std::ofstream(bad) << text;
    try {
      eval::read_reference(bad);
      FAIL("accepted: " << text);
    } catch (const io::Error& e) {
      const std::string msg = e.what();
      CHECK(msg.find("bad.txt") != std::string::npos);
      CHECK_MESSAGE(msg.find(what) != std::string::npos, msg);
    }
  };
  fails("ground 0\nsphere 0 0 0 1\n", "line 2: unknown shape 'sphere'");
  fails("ellipsoid 0 0 1 1 1\n", "expects 6 numbers, found 5");
  fails("ellipsoid 0 0 1 1 1 -1\n", "semi-axes must be > 0");
  fails("cuboid 0 0 0 1 1 1 1\n", "found more");
  fails("cuboid 1 0 0 0 1 1\n", "x0 < x1");
  fails("ellipsoid 0 0 nan 1 1 1\n", "non-finite");
  fails("ground 0\nground 1\ncuboid 0 0 0 1 1 1\n", "second ground");
  fails("# nothing\n", "no ellipsoid or cuboid");
  fails("cuboid 0 0 0 1 1 x\n", "line 1");
}

TEST_CASE("eval: a map written as .bt/.ot and read back evaluates the same") {
  const eval::Reference ref = tree_like();
  OccupancyMap<OcKey> map(0.1);
  test::Rng rng(5);
  std::uniform_real_distribution<double> u(-1.5, 1.5), uz(0.0, 2.5);
  for (int i = 0; i < 3000; ++i) {
    OcKey k;
    REQUIRE(map.grid().coord_to_key(u(rng), u(rng), uz(rng), k));
    map.set(k, (rng() % 2) ? 1.2f : -0.8f);
  }
  const eval::Metrics want = eval::evaluate(map, ref);
  const auto dir = test::scratch_dir("eval");
  for (const char* name : {"m.bt", "m.ot"}) {
    const std::string path = (dir / name).string();
    if (std::string(name) == "m.bt")
      io::write_bt(path, map);
    else
      io::write_ot(path, map);
    const eval::Metrics got = eval::evaluate(io::read_octree(path), ref);
    CAPTURE(name);
    CHECK(got.occupied == want.occupied);
    CHECK(got.free == want.free);
    CHECK(got.in_shell == want.in_shell);
    CHECK(got.covered == want.covered);
    CHECK(got.irrelevant == want.irrelevant);
    CHECK(got.free_inside == want.free_inside);
  }
}

TEST_CASE("eval: the shell count agrees with sampling every voxel of the reference's box") {
  const eval::Reference ref = tree_like();
  const Grid<OcKey> grid(0.1);
  const double r = 0.1;
  std::size_t sampled = 0;  // voxels with samples inside and outside, centre above the ground
  for (int x = -13; x < 13; ++x)
    for (int y = -12; y < 12; ++y)
      for (int z = -2; z < 25; ++z) {
        const Point3d c{(x + 0.5) * r, (y + 0.5) * r, (z + 0.5) * r};
        std::size_t in = 0;
        for (int i = 0; i <= 4; ++i)
          for (int j = 0; j <= 4; ++j)
            for (int l = 0; l <= 4; ++l)
              in += inside_sampled(
                  ref, {c.x - r / 2 + r * i / 4, c.y - r / 2 + r * j / 4, c.z - r / 2 + r * l / 4});
        sampled += in > 0 && in < 125 && c.z > 0;
      }
  const std::size_t exact = eval::count_shell(grid, ref);
  CHECK(exact >= sampled);  // sampling misses voxels that only graze a surface
  CHECK(exact <= sampled + sampled / 20);
  CHECK(sampled > 1000);
  // A reference too large to walk is refused, not walked for hours.
  eval::Reference huge;
  huge.cuboids.push_back({{-1000, -1000, 0}, {1000, 1000, 10}});
  CHECK_THROWS_AS(eval::count_shell(Grid<OcKey>(0.05), huge), std::invalid_argument);
  // The limit is a parameter: this reference's box (grown by a voxel) is about 21 x 19 x 26 voxels.
  CHECK_THROWS_AS(eval::count_shell(grid, ref, 5000), std::invalid_argument);
  CHECK(eval::count_shell(grid, ref, 50000) == exact);
  eval::MetricOptions small;
  small.max_shell_box = 5000;
  const OccupancyMap<OcKey> empty(0.1);
  CHECK_THROWS_AS(eval::evaluate(empty, ref, small), std::invalid_argument);
  CHECK(eval::evaluate(empty, ref).shell == exact);
}
