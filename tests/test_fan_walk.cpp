// The dense ray walks (raycast/detail/fan_walk.hpp): every walk path marks exactly the voxels of
// compute_ray_keys; the eight-ray set-up equals setup_walk bit for bit; end_point_clear's claim.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <list>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include <knnocc/insertion/scan_inserter.hpp>

#include "test_support.hpp"

using knnocc::OccupancyMap;
using knnocc::OcKey;
using knnocc::Point3f;
using knnocc::WideKey;

TEST_CASE("fan_walk.lanes_walk_the_scalar_voxels") {
  // Rays of every kind through one box: random, axis-aligned, planar, exact diagonals through
  // voxel corners (ties), one-voxel and zero-length ones, negative coordinates. Every walk
  // insert_point_cloud may use (four lanes on AVX2 machines, two groups of eight on AVX-512
  // ones) and the one-ray walk against compute_ray_keys, bit for bit and visit for visit.
  knnocc::test::Rng rng(5);
  for (const double res : {0.1, 0.5, 0.07}) {
    CAPTURE(res);
    const knnocc::Grid<OcKey> grid(res);
    std::uniform_real_distribution<float> u(-3.f, 3.f);
    std::uniform_int_distribution<int> kind(0, 9), cell(-6, 6);
    std::vector<std::pair<Point3f, Point3f>> rays;
    for (int i = 0; i < 4000; ++i) {
      Point3f o{u(rng), u(rng), u(rng)}, e{u(rng), u(rng), u(rng)};
      switch (kind(rng)) {
        case 0:
          e.y = o.y, e.z = o.z;
          break;  // along x
        case 1:
          e.z = o.z;
          break;   // in a plane
        case 2: {  // through voxel corners
          const float c = static_cast<float>(res) * 0.5f;
          o = {c * cell(rng), c * cell(rng), c * cell(rng)};
          const float d = static_cast<float>(res) * static_cast<float>(cell(rng));
          e = {o.x + d, o.y + d, o.z - d};
          break;
        }
        case 3:
          e = {o.x + 0.01f, o.y, o.z};
          break;  // tiny
        case 4:
          e = o;
          break;  // zero length
        default:
          break;
      }
      rays.emplace_back(o, e);
    }
    // The box: every key the rays touch, grown by one voxel (as ScanInserter's dense box).
    std::int64_t lo[3] = {1 << 20, 1 << 20, 1 << 20}, hi[3] = {-1, -1, -1};
    std::vector<std::vector<OcKey>> keys;
    for (const auto& [o, e] : rays) {
      keys.emplace_back();
      knnocc::compute_ray_keys(grid, o, e, keys.back());
      OcKey k;
      for (const Point3f& p : {o, e}) {
        REQUIRE(grid.point_to_key(p, k));
        for (int a = 0; a < 3; ++a) {
          lo[a] = std::min<std::int64_t>(lo[a], k[a] - 1);
          hi[a] = std::max<std::int64_t>(hi[a], k[a] + 1);
        }
      }
    }
    knnocc::detail::ScanBitmap box;
    std::int64_t base[3], size[3];
    for (int a = 0; a < 3; ++a) {
      base[a] = lo[a] / 8 * 8;
      size[a] = ((hi[a] + 1 - base[a]) + 63) / 64 * 64;
    }
    box.reshape(base, size);
    const std::size_t words = static_cast<std::size_t>((size[0] * size[1] * size[2] + 63) / 64);
    // Chunks of 7, 13 and 41 rays: four lanes refill and drain on the scalar walk in every chunk;
    // sixteen stream lanes park from the start in the short chunks and refill and park in the
    // long ones; bundles are part parked (7, 13) or take a second bundle (41); and a voxel missed
    // by one ray is rarely hidden by another ray of the same chunk.
    std::size_t walked = 0, clear = 0;
    for (std::size_t first = 0, chunk = 7; first < rays.size();
         first += chunk, chunk = chunk == 7    ? 13
                                 : chunk == 13 ? 41
                                               : 7) {
      std::vector<knnocc::detail::LinearRay> linear;
      std::vector<std::uint64_t> expected(words, 0);
      std::size_t expected_visits = 0;
      for (std::size_t i = first; i < std::min(rays.size(), first + chunk); ++i) {
        knnocc::RayWalk<OcKey> w;
        if (knnocc::start_ray(grid, rays[i].first, rays[i].second, w) != knnocc::RayStart::walk) {
          CHECK(keys[i].empty());
          continue;
        }
        knnocc::detail::LinearRay r;
        r.state = w.state;
        r.index = box.index(w.origin[0], w.origin[1], w.origin[2]);
        r.end_index = box.index(w.end[0], w.end[1], w.end[2]);
        for (int a = 0; a < 3; ++a) r.stride[a] = w.step[a] * box.stride(a);
        // The lane walks end a ray with a clear end by its step count (four lanes: test only its
        // last step), as in ScanInserter.
        const std::int32_t ko[3] = {w.origin[0], w.origin[1], w.origin[2]};
        const std::int64_t stride[3] = {box.stride(0), box.stride(1), box.stride(2)};
        const knnocc::detail::RayFan fan(grid, rays[i].first, ko, base, stride);
        const knnocc::detail::RayEnd end{rays[i].second, {w.end[0], w.end[1], w.end[2]}};
        r.clear_end = knnocc::detail::end_point_clear<OcKey>(fan, end, r.state.length);
        clear += r.clear_end;
        linear.push_back(r);
        expected_visits += keys[i].size();
        for (const OcKey& k : keys[i])
          knnocc::detail::set_bit(expected.data(), box.index(k[0], k[1], k[2]));
      }
      // Every walk path this CPU runs, over the chunk as a ray stream and as blocks, with bit marks
      // and with byte marks (on the bundles path a stream goes on the AVX-512 stream lanes).
      knnocc::detail::ScanBitmap bytemap;
      bytemap.reshape(base, size, true);
      const auto block = std::make_unique<knnocc::detail::RayBlock>();
      using knnocc::detail::WalkPath;
      for (const WalkPath path : {WalkPath::scalar, WalkPath::avx2_lanes, WalkPath::avx512_stream,
                                  WalkPath::avx512_bundles})
        for (const bool as_blocks : {false, true})
          for (const bool byte_marks : {false, true}) {
            if (!knnocc::detail::walk_path_available(path)) continue;
            std::vector<std::uint64_t> bits(words, 0);
            const knnocc::detail::BitMarks bit_marks{bits.data()};
            const knnocc::detail::ByteMarks byte_marks_to{bytemap.bytes()};
            std::size_t next = 0;
            auto source = [&]() -> const knnocc::detail::LinearRay* {
              return next == linear.size() ? nullptr : &linear[next++];
            };
            // walk(marks): every ray of the chunk on the path.
            auto walk = [&](auto marks) -> std::size_t {
              if (!as_blocks) return knnocc::detail::walk_linear_rays(path, source, marks);
              std::size_t visits = 0;  // blocks of at most RayBlock::kRays rays
              for (std::size_t b = 0; b < linear.size(); b += knnocc::detail::RayBlock::kRays) {
                const std::size_t n = std::min(knnocc::detail::RayBlock::kRays, linear.size() - b);
                for (std::size_t i = 0; i < n; ++i) block->set(i, linear[b + i]);
                block->close(n);
                visits += knnocc::detail::walk_ray_block(path, *block, marks);
              }
              return visits;
            };
            if (linear.empty()) continue;
            std::size_t visits = 0;
            if (byte_marks) {
              visits = walk(byte_marks_to);
              // The byte map read back as bits, and zero again, through take_brick_row.
              std::vector<knnocc::VoxelMask> masks(static_cast<std::size_t>(bytemap.bricks(0)));
              for (std::int64_t bz = 0; bz < bytemap.bricks(2); ++bz)
                for (std::int64_t by = 0; by < bytemap.bricks(1); ++by) {
                  for (auto& m : masks) m.clear();
                  bytemap.take_brick_row(by, bz, masks.data());
                  for (std::int64_t bx = 0; bx < bytemap.bricks(0); ++bx)
                    for (int v = 0; v < knnocc::kBrickVoxels; ++v)
                      if (masks[static_cast<std::size_t>(bx)].test(v))
                        knnocc::detail::set_bit(bits.data(),
                                                bytemap.index(base[0] + bx * 8 + (v & 7),
                                                              base[1] + by * 8 + ((v >> 3) & 7),
                                                              base[2] + bz * 8 + (v >> 6)));
                }
              bytemap.mark_clean();
            } else {
              visits = walk(bit_marks);
            }
            CAPTURE(static_cast<int>(path));
            CAPTURE(as_blocks);
            CAPTURE(byte_marks);
            CHECK(visits == expected_visits);
            CHECK(bits == expected);
          }
      walked += expected_visits;
    }
    MESSAGE(walked << " voxels walked at resolution " << res << ", " << clear
                   << " rays with a clear end");
    CHECK(clear > 1000);  // both kinds of lanes walk
  }
  const auto tested = [](knnocc::detail::WalkPath path) {
    return std::string(knnocc::detail::walk_path_available(path) ? "tested"
                                                                 : "not available on this CPU");
  };
  MESSAGE("AVX2 lane walk: " << tested(knnocc::detail::WalkPath::avx2_lanes)
                             << "; AVX-512 lane walks: "
                             << tested(knnocc::detail::WalkPath::avx512_stream));
}

TEST_CASE("fan_walk.simd_ray_setup_matches_setup_walk") {
  // setup_linear_rays (eight rays at a time with AVX2, the rest one by one) against
  // setup_linear_ray (setup_walk), field by field and bit for bit, on rays in every direction,
  // along axes and in planes.
  knnocc::test::Rng rng(8);
  std::uniform_real_distribution<float> u(-30.f, 30.f);
  for (const double res : {0.1, 0.05, 0.37}) {
    const knnocc::Grid<OcKey> grid(res);
    const Point3f origin{u(rng) * 0.1f, u(rng) * 0.1f, u(rng) * 0.1f};
    OcKey ko;
    REQUIRE(grid.point_to_key(origin, ko));
    const std::int32_t okey[3] = {ko[0], ko[1], ko[2]};
    const std::int64_t lo[3] = {ko[0] - 1000, ko[1] - 1000, ko[2] - 1000};
    const std::int64_t stride[3] = {1, 4096, 4096 * 4096};
    const knnocc::detail::RayFan fan(grid, origin, okey, lo, stride);
    std::vector<knnocc::detail::RayEnd> rays;
    for (int i = 0; i < 4003; ++i) {
      Point3f e{u(rng), u(rng), u(rng)};
      if (i % 7 == 1) e.x = origin.x;
      if (i % 11 == 2) e.y = origin.y, e.z = origin.z;
      OcKey ke;
      REQUIRE(grid.point_to_key(e, ke));
      if (ke == ko) continue;
      rays.push_back({e, {ke[0], ke[1], ke[2]}});
    }
    std::vector<knnocc::detail::LinearRay> fast(rays.size()), slow(rays.size());
    knnocc::detail::setup_linear_rays(grid, fan, rays.data(), rays.size(), fast.data());
    for (std::size_t i = 0; i < rays.size(); ++i)
      knnocc::detail::setup_linear_ray(grid, fan, rays[i], slow[i]);
    std::size_t differing = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const auto& a = fast[i];
      const auto& b = slow[i];
      bool same = a.index == b.index && a.end_index == b.end_index &&
                  a.state.length == b.state.length &&
                  a.state.steps_to_end == b.state.steps_to_end && a.clear_end == b.clear_end;
      for (int k = 0; k < 3; ++k)
        same = same && a.stride[k] == b.stride[k] && a.state.t_max[k] == b.state.t_max[k] &&
               a.state.t_delta[k] == b.state.t_delta[k];
      differing += !same;
    }
    CHECK(differing == 0);
  }
  // A degenerate ray: the end points straddle the border at 0 by 1e-30 m, so the squared length
  // underflows to 0 and the direction is inf / NaN (OctoMap's arithmetic, repeated exactly).
  const knnocc::Grid<OcKey> grid(0.1);
  const Point3f o{-1e-30f, 0.01f, 0.01f}, e{1e-30f, 0.01f, 0.01f};
  OcKey ko, ke;
  REQUIRE(grid.point_to_key(o, ko));
  REQUIRE(grid.point_to_key(e, ke));
  REQUIRE(ko != ke);
  const std::int32_t okey[3] = {ko[0], ko[1], ko[2]};
  const std::int64_t lo[3] = {ko[0] - 8, ko[1] - 8, ko[2] - 8};
  const std::int64_t stride[3] = {1, 64, 64 * 64};
  const knnocc::detail::RayFan fan(grid, o, okey, lo, stride);
  const knnocc::detail::RayEnd ray{e, {ke[0], ke[1], ke[2]}};
  const std::vector<knnocc::detail::RayEnd> rays(12, ray);  // eight at once, then one by one
  std::vector<knnocc::detail::LinearRay> fast(12);
  knnocc::detail::setup_linear_rays(grid, fan, rays.data(), 12, fast.data());
  knnocc::detail::LinearRay slow;
  knnocc::detail::setup_linear_ray(grid, fan, ray, slow);
  CHECK_FALSE(slow.clear_end);
  for (const int i : {3, 11}) {
    CAPTURE(i);
    CHECK_FALSE(fast[i].clear_end);
    CHECK(fast[i].end_index == slow.end_index);
    CHECK(fast[i].state.steps_to_end == slow.state.steps_to_end);
    for (int a = 0; a < 3; ++a) {
      CHECK(fast[i].stride[a] == slow.stride[a]);
      CHECK(std::memcmp(&fast[i].state.t_max[a], &slow.state.t_max[a], sizeof(double)) == 0);
      CHECK(std::memcmp(&fast[i].state.t_delta[a], &slow.state.t_delta[a], sizeof(double)) == 0);
    }
  }
  std::vector<OcKey> keys;
  REQUIRE(knnocc::compute_ray_keys(grid, o, e, keys));
  CHECK(keys.size() == 1);  // the origin voxel; the next step lands on the end voxel
}

TEST_CASE("fan_walk.clear_end_points_end_on_their_voxel") {
  // end_point_clear() lets the lane walks end a ray by its step count, with no end test at all.
  // Its claim, checked on the one-ray walk: a flagged ray ends on its end voxel after exactly
  // steps_to_end steps, not earlier by its length and not past the voxel. The end points lie 0-40
  // float steps from a voxel border along one to three axes, where some rays do end otherwise
  // (the test asserts that it meets such rays, so that it could catch a margin too small).
  knnocc::test::Rng rng(13);
  std::size_t flagged = 0, other_end = 0, flagged_other_end = 0, rays = 0;
  for (const double res : {0.05, 0.1, 0.37}) {
    CAPTURE(res);
    const knnocc::Grid<OcKey> grid(res);
    std::uniform_real_distribution<float> u(-1.f, 1.f), far(-40.f, 40.f);
    std::uniform_int_distribution<int> ulps(-40, 40), cell(-400, 400), axes(0, 7);
    const std::int64_t lo[3] = {0, 0, 0},
                       stride[3] = {1, std::int64_t{1} << 17, std::int64_t{1} << 34};
    for (int i = 0; i < 30000; ++i) {
      const Point3f o{u(rng), u(rng), u(rng)};
      Point3f e{far(rng), far(rng), far(rng)};
      if (i % 3 == 0) e = {o.x + u(rng), o.y + u(rng), o.z + u(rng)};  // short rays too
      const int snap = axes(rng);  // which coordinates go next to a border (0: none)
      float* c[3] = {&e.x, &e.y, &e.z};
      for (int a = 0; a < 3; ++a) {
        if (!((snap >> a) & 1)) continue;
        float v = static_cast<float>(cell(rng) * res);
        for (int k = ulps(rng); k != 0; k += k > 0 ? -1 : 1)
          v = std::nextafter(v, k > 0 ? INFINITY : -INFINITY);
        *c[a] = v;
      }
      OcKey ko, ke;
      REQUIRE(grid.point_to_key(o, ko));
      REQUIRE(grid.point_to_key(e, ke));
      if (ko == ke) continue;
      const std::int32_t okey[3] = {ko[0], ko[1], ko[2]};
      const knnocc::detail::RayFan fan(grid, o, okey, lo, stride);
      knnocc::detail::LinearRay r;
      knnocc::detail::setup_linear_ray(grid, fan, {e, {ke[0], ke[1], ke[2]}}, r);
      knnocc::IndexPosition at{r.index, r.stride, r.end_index};
      std::size_t visits = 0;
      knnocc::walk_ray(r.state, at, [&](const knnocc::IndexPosition&) { return ++visits, true; });
      const bool on_end =
          at.index == r.end_index && visits + 1 == static_cast<std::size_t>(r.state.steps_to_end);
      ++rays;
      flagged += r.clear_end;
      other_end += !on_end;
      flagged_other_end += r.clear_end && !on_end;
    }
  }
  MESSAGE(rays << " rays, " << flagged << " with a clear end, " << other_end
               << " ending elsewhere than on their end voxel's step");
  CHECK(flagged_other_end == 0);
  CHECK(other_end > 100);      // the rays the flag must leave out are there
  CHECK(flagged > rays / 10);  // and the flag is not simply always false
}
