// Multithreaded insertion and the two scratch paths give the very same map: same voxels, same
// log-odds, same storage order, same statistics, for 1, 2, 4 and 8 threads. The 4-rays-at-once
// walk sets exactly the voxels of the scalar walk and of compute_ray_keys.
// (The insert_threads.* cases also run under ThreadSanitizer: ctest -R tsan.)
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
#include <knnocc/io/xyz.hpp>
#include <knnocc/raycast/detail/fan_walk.hpp>

#include "test_support.hpp"

using knnocc::OccupancyMap;
using knnocc::OcKey;
using knnocc::Point3f;
using knnocc::WideKey;

namespace {

using knnocc::test::Scan;

// A room-like scene: most points on walls and a floor, some inside, a few far away or invalid.
std::vector<Scan> random_scans(std::uint64_t seed, int scans, int points) {
  knnocc::test::Rng rng(seed);
  std::uniform_real_distribution<float> u(-6.f, 6.f), o(-0.5f, 0.5f), unit(0.f, 1.f);
  std::vector<Scan> out(static_cast<std::size_t>(scans));
  for (auto& s : out) {
    s.origin = {o(rng), o(rng), 1.0f + o(rng)};
    for (int i = 0; i < points; ++i) {
      Point3f p{u(rng), u(rng), u(rng) * 0.4f};
      const float r = unit(rng);
      if (r < 0.3f)
        p.z = 0.0f;  // floor
      else if (r < 0.6f)
        p.x = p.x < 0 ? -6.f : 6.f;  // walls
      else if (r < 0.602f)
        p.x *= 4.0f;  // far
      else if (r < 0.603f)
        p.y = std::nanf("");  // invalid
      s.points.push_back(p);
    }
  }
  return out;
}

template <class Key>
struct Outcome {
  std::vector<std::tuple<std::uint64_t, float>> voxels;  // in storage order
  std::vector<std::size_t> stats;                        // per scan: keys, occupied, free, ...

  bool operator==(const Outcome& o) const { return voxels == o.voxels && stats == o.stats; }
};

template <class Key>
Outcome<Key> insert(const std::vector<Scan>& scans, double res, unsigned threads,
                    std::size_t scratch_limit, double max_range = -1.0, bool discretize = false) {
  OccupancyMap<Key> map(res);
  knnocc::ScanInserter<Key> inserter(map, {}, threads);
  inserter.set_scratch_limit(scratch_limit);
  Outcome<Key> out;
  for (const auto& s : scans) {
    const auto st = inserter.insert_point_cloud(s.origin, s.points, max_range, discretize);
    out.stats.insert(out.stats.end(),
                     {st.points, st.nonfinite, st.out_of_range, st.beyond_max_range, st.ray_keys,
                      st.occupied_voxels, st.free_voxels});
  }
  map.for_each_voxel([&](const Key& k, float v) { out.voxels.emplace_back(k.pack(), v); });
  return out;
}

constexpr std::size_t kDefaultLimit = std::size_t{128} << 20;

}  // namespace

TEST_CASE_TEMPLATE("insert_threads.identical_maps", Key, OcKey, WideKey) {
  // 12,000 points per scan: collect() splits the points between the threads too (from 8,192).
  const auto scans = random_scans(7, 3, 12000);
  for (const double max_range : {-1.0, 3.0}) {
    for (const bool discretize : {false, true}) {
      CAPTURE(max_range);
      CAPTURE(discretize);
      const auto one = insert<Key>(scans, 0.1, 1, kDefaultLimit, max_range, discretize);
      REQUIRE(one.voxels.size() > 10000);
      for (const unsigned threads : {2u, 4u, 8u}) {
        CAPTURE(threads);
        CHECK(insert<Key>(scans, 0.1, threads, kDefaultLimit, max_range, discretize) == one);
        // The hashed scratch (what a scan too large for the dense one takes) agrees too.
        CHECK(insert<Key>(scans, 0.1, threads, 0, max_range, discretize) == one);
      }
      CHECK(insert<Key>(scans, 0.1, 1, 0, max_range, discretize) == one);
    }
  }
}

TEST_CASE("insert_threads.scratch_limit_picks_the_path_not_the_map") {
  // Scans whose box is too large for the dense scratch under a given limit fall back to the
  // hashed one; in between, some scans of a sequence take one path and some the other.
  const auto scans = random_scans(11, 6, 3000);
  const auto reference = insert<OcKey>(scans, 0.05, 1, kDefaultLimit);
  for (const std::size_t limit :
       {std::size_t{0}, std::size_t{5} << 20, std::size_t{8} << 20, std::size_t{16} << 20}) {
    CAPTURE(limit);
    CHECK(insert<OcKey>(scans, 0.05, 1, limit) == reference);
    CHECK(insert<OcKey>(scans, 0.05, 3, limit) == reference);
  }
}

TEST_CASE("insert_threads.scan_dat") {
  std::vector<Scan> scans(1);
  scans[0].points = knnocc::test::scan_dat_points_or_skip();
  if (scans[0].points.empty()) return;
  const auto one = insert<OcKey>(scans, 0.1, 1, kDefaultLimit);
  CHECK(one.stats[4] == 7066778);  // ray keys, as liboctomap's computeRayKeys
  for (const unsigned threads : {2u, 4u, 8u}) {
    CAPTURE(threads);
    CHECK(insert<OcKey>(scans, 0.1, threads, kDefaultLimit) == one);
  }
  CHECK(insert<OcKey>(scans, 0.1, 2, 0) == one);
}

TEST_CASE("insert_threads.lanes_walk_the_scalar_voxels") {
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

TEST_CASE("insert_threads.simd_ray_setup_matches_setup_walk") {
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

TEST_CASE("insert_threads.clear_end_points_end_on_their_voxel") {
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

TEST_CASE("insert_threads.byte_marks_build_the_same_map") {
  // A scan whose rays take more than 4 M steps in a box of under 4 M voxels marks its free
  // voxels in bytes (ScanStats::byte_marks) where the CPU has AVX-512 (elsewhere bits): the same
  // map as with bit marks (a scratch limit too small for bytes), the hashed scratch and any thread
  // count. Points on and near the walls of a 6 m cube around the origin at 0.05 m: a box of about
  // 130^3 voxels, rays of about 100 steps. The scan goes in chunks (a vector) and in one piece (a
  // list), and the second scan reuses the bytes.
  knnocc::test::Rng rng(29);
  std::uniform_real_distribution<float> u(-3.f, 3.f);
  std::uniform_int_distribution<int> face(0, 5);
  std::vector<Scan> scans(2);
  for (std::size_t s = 0; s < scans.size(); ++s) {
    scans[s].origin = {0.013f + 0.2f * static_cast<float>(s), -0.021f, 0.034f};
    for (int i = 0; i < 60000; ++i) {
      Point3f p{u(rng), u(rng), u(rng)};
      const int f = face(rng);
      // Two in three on a wall, exactly on a voxel border (rays without a clear end); the rest
      // inside, on the wall's plane moved by a random part of a voxel (rays with a clear end).
      (f < 2 ? p.x : f < 4 ? p.y : p.z) = (f % 2 ? 3.f : -3.f) * (i % 3 ? 1.f : 0.99f);
      scans[s].points.push_back(p);
    }
  }
  bool avx512 = false;
#if KNNOCC_AVX2_LANES && !defined(KNNOCC_NO_AVX512)
  avx512 = knnocc::detail::cpu_has_avx512();
#endif
  auto run = [&](unsigned threads, std::size_t limit, bool listed, bool bytes_if_avx512) {
    const bool expect_bytes = bytes_if_avx512 && avx512;
    OccupancyMap<OcKey> map(0.05);
    knnocc::ScanInserter<OcKey> inserter(map, {}, threads);
    inserter.set_scratch_limit(limit);
    Outcome<OcKey> out;
    for (const auto& s : scans) {
      const auto st = listed ? inserter.insert_point_cloud(
                                   s.origin, std::list<Point3f>(s.points.begin(), s.points.end()))
                             : inserter.insert_point_cloud(s.origin, s.points);
      CHECK(st.byte_marks == expect_bytes);
      CHECK(st.ray_keys > (std::size_t{4} << 20));
      out.stats.insert(out.stats.end(), {st.ray_keys, st.occupied_voxels, st.free_voxels});
    }
    map.for_each_voxel([&](const OcKey& k, float v) { out.voxels.emplace_back(k.pack(), v); });
    return out;
  };
  const auto bytes = run(1, kDefaultLimit, false, true);
  REQUIRE(bytes.voxels.size() > 100000);
  MESSAGE("byte marks: " << (avx512 ? "tested" : "not used on this CPU (no AVX-512)"));
  // Bits: room for two bitmaps of the box (about 0.6 MB) but not for a byte map (2.2 MB).
  CHECK(run(1, std::size_t{1} << 20, false, false) == bytes);
  CHECK(run(1, 0, false, false) == bytes);  // hashed
  CHECK(run(1, kDefaultLimit, true, true) == bytes);
  for (const unsigned threads : {2u, 4u}) {
    CAPTURE(threads);
    CHECK(run(threads, kDefaultLimit, false, true) == bytes);
    CHECK(run(threads, kDefaultLimit, true, true) == bytes);
  }
}
