// ScanInserter's threads and scratch paths give the very same map: same voxels, same log-odds,
// same storage order, same statistics, for 1, 2, 4 and 8 threads, dense and hashed scratch, bit and
// byte marks. (The insert_threads.* cases also run under ThreadSanitizer: ctest -R tsan.)
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <list>
#include <memory>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <knnocc/insertion/scan_inserter.hpp>
#include <knnocc/map/detail/brick_access.hpp>

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

TEST_CASE("insert_threads.sparse_rays_leave_uniform_bricks") {
  // Long sparse rays (hashed scratch) leave many bricks that one scan only misses, and solid
  // blocks of endpoints filling whole bricks leave bricks that it only hits (their misses are
  // hits too): such a new brick takes its one update as a uniform brick, without a value array,
  // in whichever thread updates it. The map must not depend on the thread count (a value array
  // allocated from a worker thread, or two bricks sharing one, would change it).
  knnocc::test::Rng rng(41);
  std::uniform_real_distribution<float> far(-40.f, 40.f);
  std::uniform_int_distribution<int> block(-60, 60);
  const double res = 0.1;
  std::vector<Scan> scans(2);
  std::vector<std::uint64_t> solid;  // packed coordinates of the bricks filled with endpoints
  for (std::size_t s = 0; s < scans.size(); ++s) {
    scans[s].origin = {0.013f + 0.3f * static_cast<float>(s), -0.021f, 0.034f};
    for (int i = 0; i < 600; ++i) scans[s].points.push_back({far(rng), far(rng), far(rng)});
    for (int c = 0; c < 300; ++c) {  // a brick 5.6-6.4 m away (1 brick = 8 voxels = 0.8 m)
      std::array<int, 3> b{block(rng) / 10, block(rng) / 10, block(rng) / 10};
      b[static_cast<std::size_t>(c % 3)] = c % 2 ? 7 : -8;
      for (int i = 0; i < knnocc::kBrickVoxels; ++i) {
        const int x = i % 8, y = i / 8 % 8, z = i / 64;
        scans[s].points.push_back({static_cast<float>(((b[0] * 8 + x) + 0.5) * res),
                                   static_cast<float>(((b[1] * 8 + y) + 0.5) * res),
                                   static_cast<float>(((b[2] * 8 + z) + 0.5) * res)});
      }
      if (s == 0)
        solid.push_back(knnocc::BrickLayout<OcKey>::brick_of(
            OcKey{static_cast<std::uint16_t>(b[0] * 8 + 32768),
                  static_cast<std::uint16_t>(b[1] * 8 + 32768),
                  static_cast<std::uint16_t>(b[2] * 8 + 32768)}));
    }
  }
  for (const std::size_t limit : {std::size_t{0}, kDefaultLimit}) {
    CAPTURE(limit);
    // After the first scan: the solid bricks are uniform (every voxel a hit) and most of the
    // bricks the rays cross have no value array either.
    OccupancyMap<OcKey> map(res);
    knnocc::ScanInserter<OcKey> inserter(map, {}, 3);
    inserter.set_scratch_limit(limit);
    inserter.insert_point_cloud(scans[0].origin, scans[0].points);
    std::size_t uniform = 0;
    for (const auto& b : knnocc::detail::brick_reader(map).bricks())
      uniform += b.values == nullptr && b.known.any();
    CHECK(uniform > map.num_bricks() / 2);
    if (limit == 0) {
      // The hashed scratch is applied in place: 8 bytes per touched brick (its order and map
      // slot, vectors at most twice their size) beside it, no 144-byte record per brick.
      const auto used = inserter.scratch_usage();
      REQUIRE(used.hashed > 0);
      CHECK(used.brick_groups > 0);
      CHECK(used.brick_groups <= 4 * sizeof(std::uint32_t) * map.num_bricks());
    }
    for (const std::uint64_t coord : solid) {
      const auto* b = knnocc::detail::brick_reader(map).find_brick(coord);
      REQUIRE(b != nullptr);
      CHECK(b->values == nullptr);
      CHECK(b->known.count() == knnocc::kBrickVoxels);
      CHECK(b->uniform == knnocc::OctoMapModel{}.hit);
    }
    // Both scans (the second updates uniform bricks again): the same map for any thread count.
    const auto one = insert<OcKey>(scans, res, 1, limit);
    REQUIRE(one.voxels.size() > 100000);
    for (const unsigned threads : {2u, 3u, 4u, 8u}) {
      CAPTURE(threads);
      CHECK(insert<OcKey>(scans, res, threads, limit) == one);
    }
  }
}

TEST_CASE("insert_threads.memory_limit_covers_the_scratch") {
  // Long sparse rays touch about 2 M bricks: their hashed scratch alone (about 140 bytes a
  // brick and thread) is far above a 48 MB map limit, which now bounds map and scratch together:
  // the scan is refused with MemoryLimitError and neither grew past the limit. Under a limit
  // that holds the scan, the map is the one built without a limit.
  knnocc::test::Rng rng(43);
  std::uniform_real_distribution<float> far(-400.f, 400.f), near(-20.f, 20.f);
  std::vector<Scan> big(1), small(1);
  big[0].origin = small[0].origin = {0.013f, -0.021f, 0.034f};
  for (int i = 0; i < 3000; ++i) big[0].points.push_back({far(rng), far(rng), far(rng)});
  for (int i = 0; i < 3000; ++i) small[0].points.push_back({near(rng), near(rng), near(rng)});
  constexpr std::size_t kLimit = std::size_t{48} << 20;
  for (const unsigned threads : {1u, 2u, 3u}) {
    CAPTURE(threads);
    OccupancyMap<OcKey> map(0.1);
    map.set_memory_limit(kLimit);
    knnocc::ScanInserter<OcKey> inserter(map, {}, threads);
    CHECK_THROWS_AS(inserter.insert_point_cloud(big[0].origin, big[0].points),
                    knnocc::MemoryLimitError);
    CHECK(map.memory_usage() + inserter.memory_usage() <= kLimit);
    CHECK(map.memory_limit() == kLimit);  // restored after the refusal
  }
  const auto unlimited = insert<OcKey>(small, 0.1, 1, kDefaultLimit);
  for (const unsigned threads : {1u, 3u}) {
    CAPTURE(threads);
    for (const std::size_t scratch : {std::size_t{0}, kDefaultLimit}) {
      OccupancyMap<OcKey> map(0.1);
      map.set_memory_limit(kLimit);
      knnocc::ScanInserter<OcKey> inserter(map, {}, threads);
      inserter.set_scratch_limit(scratch);
      inserter.insert_point_cloud(small[0].origin, small[0].points);
      CHECK(map.memory_usage() + inserter.memory_usage() <= kLimit);
      Outcome<OcKey> out;
      map.for_each_voxel([&](const OcKey& k, float v) { out.voxels.emplace_back(k.pack(), v); });
      CHECK(out.voxels == unlimited.voxels);
    }
  }
}

TEST_CASE("insert_threads.one_thread_applies_the_dense_scratch_without_brick_records") {
  // One thread and no map memory limit: the dense scratch goes into the map brick row by brick
  // row, with no record per touched brick (ScratchUsage::brick_groups stays 0), and a scan with
  // few points for its box (the room spread 4 times wider, rays cut at 8 m) keeps its hits as
  // codes, with no hit bitmap. The map is the one the two-step path builds (two threads, or one
  // under a memory limit): same voxels in storage order, same statistics, same memory (a fresh
  // map's room for the first scan's bricks), same changes recorded under change detection.
  const auto room = random_scans(5, 2, 12000);
  struct Run {
    std::vector<std::tuple<std::uint64_t, float>> voxels;
    std::vector<std::size_t> stats;
    std::size_t memory = 0;
    std::vector<std::pair<std::uint64_t, bool>> changes;
    bool operator==(const Run& o) const {
      return voxels == o.voxels && stats == o.stats && memory == o.memory && changes == o.changes;
    }
  };
  for (const bool changes : {false, true})
    for (const float spread : {1.0f, 4.0f}) {
      CAPTURE(changes);
      CAPTURE(spread);
      auto scans = room;
      for (auto& s : scans)
        for (auto& p : s.points) p = Point3f{p.x * spread, p.y * spread, p.z * spread};
      const double max_range = spread > 1 ? 8.0 : 4.0;
      std::vector<Run> runs;
      // one thread (the new path), two threads, one thread under a memory limit (both two-step)
      for (const unsigned threads : {1u, 2u}) {
        for (const std::size_t limit : {std::size_t{0}, std::size_t{1} << 30}) {
          if (threads == 2 && limit) continue;
          CAPTURE(threads);
          CAPTURE(limit);
          OccupancyMap<OcKey> map(0.1);
          map.enable_change_detection(changes);
          map.set_memory_limit(limit);
          knnocc::ScanInserter<OcKey> inserter(map, {}, threads);
          Run run;
          for (const auto& s : scans) {
            const auto st = inserter.insert_point_cloud(s.origin, s.points, max_range);
            REQUIRE(st.chunks > 1);  // the chunked path, dense scratch
            run.stats.insert(run.stats.end(), {st.ray_keys, st.occupied_voxels, st.free_voxels});
          }
          const knnocc::ScratchUsage used = inserter.scratch_usage();
          CHECK((used.hit_bitmaps == 0) == (spread > 1 && threads == 1 && limit == 0));
          CHECK(used.miss_bitmaps > 0);
          CHECK((used.brick_groups == 0) == (threads == 1 && limit == 0));
          run.voxels.reserve(map.num_voxels());
          map.for_each_voxel(
              [&](const OcKey& k, float v) { run.voxels.emplace_back(k.pack(), v); });
          run.memory = map.memory_usage();
          map.for_each_changed_key(
              [&](const OcKey& k, bool created) { run.changes.emplace_back(k.pack(), created); });
          std::sort(run.changes.begin(), run.changes.end());
          CHECK(run.changes.empty() != changes);
          runs.push_back(std::move(run));
        }
      }
      REQUIRE(runs.front().voxels.size() > 10000);
      for (std::size_t i = 1; i < runs.size(); ++i) {
        CAPTURE(i);
        CHECK(runs[i] == runs.front());
      }
    }
}
