// A program of its own built with -ffp-contract=fast (tests/CMakeLists.txt), as a consumer's
// gnu++17 build with GCC, or clang's default, may contract: the insertion's vector walks (whose
// AVX-512 target enables FMA) must still produce OctoMap's keys. Its own program, so that no
// inline function comes from a translation unit built otherwise. The reference is
// compute_ray_keys, compiled for the baseline target, which has no FMA to contract into.
#define DOCTEST_CONFIG_IMPLEMENT_WITH_MAIN
#include <doctest/doctest.h>

#include <optional>
#include <random>
#include <set>
#include <vector>

#include <knnocc/insertion/scan_inserter.hpp>
#include <knnocc/raycast/dda.hpp>

#include "../test_support.hpp"

using knnocc::OcKey;
using knnocc::Point3f;

TEST_CASE("fp_contract.insertion_keeps_octomap_keys") {
  knnocc::test::Rng rng(53);
  std::uniform_real_distribution<float> u(-6.f, 6.f);
  for (const int n : {3000, 20000}) {  // one piece, and chunks
    CAPTURE(n);
    std::vector<Point3f> pts;
    for (int i = 0; i < n; ++i) pts.push_back({u(rng), u(rng), u(rng) * 0.3f});
    const Point3f origin{0.013f, -0.027f, 0.31f};
    knnocc::OccupancyMap<OcKey> map(0.05);
    knnocc::ScanInserter<OcKey> inserter(map);
    const auto st = inserter.insert_point_cloud(origin, pts);

    std::set<OcKey> free_cells, occupied_cells;
    std::vector<OcKey> ray;
    std::size_t keys = 0;
    for (const Point3f& p : pts) {
      if (knnocc::compute_ray_keys(map.grid(), origin, p, ray)) {
        free_cells.insert(ray.begin(), ray.end());
        keys += ray.size();
      }
      OcKey k;
      if (map.grid().point_to_key(p, k)) occupied_cells.insert(k);
    }
    for (const OcKey& k : occupied_cells) free_cells.erase(k);
    CHECK(st.ray_keys == keys);
    CHECK(st.occupied_voxels == occupied_cells.size());
    CHECK(st.free_voxels == free_cells.size());
    std::size_t wrong = 0;
    for (const OcKey& k : free_cells) wrong += !(map.is_occupied(k) == std::optional<bool>(false));
    for (const OcKey& k : occupied_cells)
      wrong += !(map.is_occupied(k) == std::optional<bool>(true));
    CHECK(wrong == 0);
    CHECK(map.num_voxels() == free_cells.size() + occupied_cells.size());
  }
}

TEST_CASE("fp_contract.rays_ending_on_voxel_borders") {
  // End points exactly on voxel borders (the walls of a 6 m cube at 0.05 m), where one rounding
  // of the set-up decides whether a ray's last steps happen. The walks' borders must be OctoMap's
  // float half-voxel from the voxel's centre: GCC 12's -O2 (this program's second build) once
  // vectorized that conversion away, and the dense walks then visited 43 voxels more than
  // compute_ray_keys in this scene.
  const knnocc::Grid<OcKey> grid(0.05);
  const volatile float half = static_cast<float>(0.05 * 0.5);
  CHECK(grid.half_voxel_float() == static_cast<double>(half));
  const std::int32_t ko[3] = {32768, 32767, 32768};
  const std::int64_t lo[3] = {32704, 32704, 32704}, stride[3] = {1, 128, 128 * 128};
  const knnocc::detail::RayFan fan(grid, Point3f{0.013f, -0.021f, 0.034f}, ko, lo, stride);
  CHECK(fan.border[0][0] == 0.025 - static_cast<double>(half));
  CHECK(fan.border[0][1] == 0.025 + static_cast<double>(half));

  knnocc::test::Rng rng(29);
  std::uniform_real_distribution<float> u(-3.f, 3.f);
  std::uniform_int_distribution<int> face(0, 5);
  std::vector<Point3f> pts;
  for (int i = 0; i < 20000; ++i) {
    Point3f p{u(rng), u(rng), u(rng)};
    const int f = face(rng);
    (f < 2 ? p.x : f < 4 ? p.y : p.z) = f % 2 ? 3.f : -3.f;
    pts.push_back(p);
  }
  const Point3f origin{0.013f, -0.021f, 0.034f};
  std::vector<OcKey> ray;
  std::set<OcKey> free_cells, occupied_cells;
  std::size_t keys = 0;
  for (const Point3f& p : pts) {
    REQUIRE(knnocc::compute_ray_keys(grid, origin, p, ray));
    free_cells.insert(ray.begin(), ray.end());
    keys += ray.size();
    OcKey k;
    REQUIRE(grid.point_to_key(p, k));
    occupied_cells.insert(k);
  }
  for (const OcKey& k : occupied_cells) free_cells.erase(k);
  for (const std::size_t limit : {std::size_t{384} << 20, std::size_t{0}}) {  // dense, hashed
    CAPTURE(limit);
    knnocc::OccupancyMap<OcKey> map(0.05);
    knnocc::ScanInserter<OcKey> inserter(map);
    inserter.set_scratch_limit(limit);
    const auto st = inserter.insert_point_cloud(origin, pts);
    CHECK(st.ray_keys == keys);
    CHECK(st.free_voxels == free_cells.size());
    CHECK(st.occupied_voxels == occupied_cells.size());
  }
}
