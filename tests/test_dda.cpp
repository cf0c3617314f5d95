// Exact DDA (raycast/dda.hpp): OctoMap's documented examples, edge cases, and a dense-sampling
// oracle on random rays.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

#include <knnocc/raycast/dda.hpp>

#include "test_support.hpp"

using knnocc::Grid;
using knnocc::OcKey;
using knnocc::Point3f;

namespace {

std::vector<std::array<int, 3>> offsets(const std::vector<OcKey>& keys) {
  std::vector<std::array<int, 3>> out;
  for (const auto& k : keys) out.push_back({k[0] - 32768, k[1] - 32768, k[2] - 32768});
  return out;
}

// Does the segment a->b meet the closed box [lo, hi] grown by eps? (slab test)
bool segment_meets_box(const Point3f& a, const Point3f& b, const double lo[3], const double hi[3],
                       double eps) {
  const double p[3] = {a.x, a.y, a.z};
  const double d[3] = {double(b.x) - a.x, double(b.y) - a.y, double(b.z) - a.z};
  double t0 = 0.0, t1 = 1.0;
  for (int i = 0; i < 3; ++i) {
    const double l = lo[i] - eps, h = hi[i] + eps;
    if (d[i] == 0.0) {
      if (p[i] < l || p[i] > h) return false;
      continue;
    }
    double ta = (l - p[i]) / d[i], tb = (h - p[i]) / d[i];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

// The oracle: (1) the walk starts in the origin voxel, is 6-connected and never repeats a voxel;
// (2) every returned voxel is met by the segment (up to eps); (3) every voxel that a dense sample
// of the segment lies in (clearly inside, not on a face) is returned, except the end voxel.
void check_against_sampling(const Grid<OcKey>& g, const Point3f& o, const Point3f& e) {
  std::vector<OcKey> ray;
  REQUIRE(knnocc::compute_ray_keys(g, o, e, ray));
  OcKey ko, ke;
  REQUIRE(g.point_to_key(o, ko));
  REQUIRE(g.point_to_key(e, ke));
  if (ko == ke) {
    CHECK(ray.empty());
    return;
  }
  REQUIRE(!ray.empty());
  CHECK(ray.front() == ko);
  std::set<OcKey> returned(ray.begin(), ray.end());
  CHECK(returned.size() == ray.size());
  CHECK(returned.count(ke) == 0);
  for (std::size_t i = 1; i < ray.size(); ++i) {
    int manhattan = 0;
    for (int a = 0; a < 3; ++a) manhattan += std::abs(int(ray[i][a]) - int(ray[i - 1][a]));
    CHECK(manhattan == 1);
  }
  const double r = g.resolution();
  for (const auto& k : ray) {
    double lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = g.index_to_coord(k[a]) - 0.5 * r;
      hi[a] = lo[a] + r;
    }
    CHECK_MESSAGE(segment_meets_box(o, e, lo, hi, 1e-3 * r), "voxel off the segment");
  }
  const double len = std::sqrt(double(e.x - o.x) * (e.x - o.x) + double(e.y - o.y) * (e.y - o.y) +
                               double(e.z - o.z) * (e.z - o.z));
  const int samples = static_cast<int>(len / r * 64) + 2;
  for (int s = 0; s <= samples; ++s) {
    const double t = double(s) / samples;
    const double p[3] = {o.x + t * (double(e.x) - o.x), o.y + t * (double(e.y) - o.y),
                         o.z + t * (double(e.z) - o.z)};
    bool clear_inside = true;
    OcKey k;
    for (int a = 0; a < 3; ++a) {
      const double f = p[a] / r - std::floor(p[a] / r);
      if (f < 1e-3 || f > 1 - 1e-3) clear_inside = false;
      k[a] = static_cast<std::uint16_t>(std::floor(p[a] / r) + 32768);
    }
    if (!clear_inside || k == ke) continue;
    CHECK_MESSAGE(returned.count(k) == 1, "sampled voxel missing from the walk");
  }
}

}  // namespace

TEST_CASE("dda.octomap_documented_example") {
  Grid<OcKey> g(0.1);
  std::vector<OcKey> ray;
  REQUIRE(knnocc::compute_ray_keys(g, {0, 0, 0}, {0.3f, 0.3f, 0}, ray));
  const std::vector<std::array<int, 3>> expected = {{0, 0, 0}, {0, 1, 0}, {1, 1, 0},
                                                    {1, 2, 0}, {2, 2, 0}, {2, 3, 0}};
  CHECK(offsets(ray) == expected);
}

TEST_CASE("dda.edge_cases") {
  Grid<OcKey> g(0.1);
  std::vector<OcKey> ray;
  SUBCASE("zero length and same voxel give no key") {
    CHECK(knnocc::compute_ray_keys(g, {1, 1, 1}, {1, 1, 1}, ray));
    CHECK(ray.empty());
    CHECK(knnocc::compute_ray_keys(g, {0.01f, 0.01f, 0.01f}, {0.09f, 0.02f, 0.05f}, ray));
    CHECK(ray.empty());
  }
  SUBCASE("axis aligned, negative direction, end voxel excluded") {
    REQUIRE(knnocc::compute_ray_keys(g, {0.05f, 0.05f, 0.05f}, {-0.45f, 0.05f, 0.05f}, ray));
    const std::vector<std::array<int, 3>> expected = {
        {0, 0, 0}, {-1, 0, 0}, {-2, 0, 0}, {-3, 0, 0}, {-4, 0, 0}};
    CHECK(offsets(ray) == expected);
  }
  SUBCASE("ties: the higher axis steps first") {
    // Exact diagonal through voxel corners: z first, then y, then x at every corner.
    Grid<OcKey> h(0.5);
    REQUIRE(knnocc::compute_ray_keys(h, {0.25f, 0.25f, 0.25f}, {1.25f, 1.25f, 1.25f}, ray));
    const std::vector<std::array<int, 3>> expected = {{0, 0, 0}, {0, 0, 1}, {0, 1, 1},
                                                      {1, 1, 1}, {1, 1, 2}, {1, 2, 2}};
    CHECK(offsets(ray) == expected);
  }
  SUBCASE("out of range endpoints give false and no key") {
    CHECK_FALSE(knnocc::compute_ray_keys(g, {0, 0, 0}, {4000.f, 0, 0}, ray));
    CHECK(ray.empty());
    CHECK_FALSE(knnocc::compute_ray_keys(g, {-4000.f, 0, 0}, {0, 0, 0}, ray));
    CHECK_FALSE(knnocc::compute_ray_keys(g, {0, 0, 0}, {std::nanf(""), 0, 0}, ray));
  }
  SUBCASE("rays near the edge of the key range stay inside it") {
    check_against_sampling(g, {-3276.75f, -3276.75f, 3276.75f}, {-3270.3f, -3276.4f, 3270.1f});
  }
  SUBCASE("truncation keeps the direction") {
    const Point3f t = knnocc::truncate_ray({1, 2, 3}, {4, 6, 3}, 2.5);
    CHECK(t.x == doctest::Approx(1 + 1.5));
    CHECK(t.y == doctest::Approx(2 + 2.0));
    CHECK(t.z == 3.0f);
  }
}

TEST_CASE("dda.dense_sampling_oracle") {
  knnocc::test::Rng rng(20261122);
  std::uniform_real_distribution<float> coord(-6.f, 6.f);
  std::uniform_int_distribution<int> axis(0, 2);
  const double resolutions[] = {0.1, 0.05, 0.37};
  int rays = 0;
  for (const double r : resolutions) {
    Grid<OcKey> g(r);
    for (int i = 0; i < 1500; ++i) {
      Point3f o{coord(rng), coord(rng), coord(rng)};
      Point3f e{coord(rng), coord(rng), coord(rng)};
      if (i % 10 == 0) {  // axis-aligned and planar rays exercise step = 0
        const int a = axis(rng);
        (a == 0 ? e.x : a == 1 ? e.y : e.z) = (a == 0 ? o.x : a == 1 ? o.y : o.z);
        if (i % 20 == 0) e.z = o.z, e.y = o.y;
      }
      if (i % 7 == 0) e = Point3f{o.x + (e.x - o.x) * 0.02f, o.y + (e.y - o.y) * 0.02f, o.z};
      check_against_sampling(g, o, e);
      ++rays;
    }
  }
  MESSAGE(rays << " random rays checked against dense sampling");
}

TEST_CASE("dda.for_each_ray_key stops where a bool visit says so") {
  const Grid<OcKey> grid(0.1);
  const Point3f o{0.05f, 0.05f, 0.05f}, e{2.37f, 1.11f, -0.83f};
  std::vector<OcKey> all;
  REQUIRE(compute_ray_keys(grid, o, e, all));
  REQUIRE(all.size() > 10);
  for (const std::size_t stop : {std::size_t{0}, std::size_t{4}, all.size() - 1}) {
    std::vector<OcKey> seen;
    CHECK(for_each_ray_key(grid, o, e, [&](const OcKey& k) {
      seen.push_back(k);
      return seen.size() <= stop;  // false once stop + 1 keys are seen
    }));
    REQUIRE(seen.size() == stop + 1);
    CHECK(std::equal(seen.begin(), seen.end(), all.begin()));
  }
}
