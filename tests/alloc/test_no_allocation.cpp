// A warmed-up ScanInserter allocates nothing: counted with the replaced global operator new of
// this binary (counting_new.hpp) and the library's own counter of large blocks
// (detail::big_allocations).
#include <doctest/doctest.h>

#include <algorithm>
#include <random>
#include <vector>

#include <knnocc/core/detail/huge_pages.hpp>
#include <knnocc/insertion/scan_inserter.hpp>

#include "../test_support.hpp"
#include "counting_new.hpp"

namespace {
// operator new and the library's large blocks (maps' value slabs, scan scratch: huge_pages.hpp).
std::size_t all_allocations() {
  return knnocc::test::allocations() + knnocc::detail::big_allocations.load();
}
}  // namespace

TEST_CASE("insert.no_allocation_once_warmed_up") {
  knnocc::test::Rng rng(17);
  std::uniform_real_distribution<float> u(-5.f, 5.f);
  // 20,000 points go in chunks, 3,000 in one piece (and discretize always in one piece).
  constexpr std::size_t kChunk = knnocc::ScanInserter<knnocc::OcKey>::chunk_points;
  for (const std::size_t n : {std::size_t{20000}, std::size_t{3000}}) {
    std::vector<knnocc::Point3f> scan(n);
    for (auto& p : scan) p = {u(rng), u(rng), u(rng) * 0.3f};

    knnocc::OccupancyMap<knnocc::OcKey> map(0.1);
    knnocc::ScanInserter<knnocc::OcKey> inserter(map);
    for (const bool discretize : {false, true}) {
      const std::size_t cold = knnocc::test::allocations();
      const std::size_t cold_big = knnocc::detail::big_allocations;
      inserter.insert_point_cloud(knnocc::Point3f{}, scan, -1.0, discretize);  // warm-up
      if (!discretize) {  // the counters do see allocations
        CHECK(knnocc::test::allocations() > cold);
        CHECK(knnocc::detail::big_allocations > cold_big);
      }
      // Again: bricks that one update made uniform get their value arrays on the second touch.
      inserter.insert_point_cloud(knnocc::Point3f{}, scan, -1.0, discretize);
      std::shuffle(scan.begin(), scan.end(), rng);
      const std::size_t before = all_allocations();
      const auto st = inserter.insert_point_cloud(knnocc::Point3f{}, scan, 4.0, discretize);
      const std::size_t allocations = all_allocations() - before;
      CAPTURE(discretize);
      CAPTURE(n);
      CHECK(st.chunks == (n > kChunk && !discretize ? (n + kChunk - 1) / kChunk : 1u));
      CHECK(st.ray_keys > 30000);
      CHECK(allocations == 0);
    }
  }
}

TEST_CASE("insert.no_allocation_once_warmed_up_with_threads") {
  knnocc::test::Rng rng(18);
  std::uniform_real_distribution<float> u(-5.f, 5.f);
  std::vector<knnocc::Point3f> scan(20000);
  for (auto& p : scan) p = {u(rng), u(rng), u(rng) * 0.3f};

  // The same kind of scan again (the per-group lists of touched bricks depend on the scan's box).
  knnocc::OccupancyMap<knnocc::OcKey> map(0.1);
  knnocc::ScanInserter<knnocc::OcKey> inserter(map, {}, 2);
  inserter.insert_point_cloud(knnocc::Point3f{}, scan, 4.0);  // warm-up: threads, scratch, map
  inserter.insert_point_cloud(knnocc::Point3f{}, scan, 4.0);  // value arrays of uniform bricks
  std::shuffle(scan.begin(), scan.end(), rng);
  const std::size_t before = all_allocations();
  const auto st = inserter.insert_point_cloud(knnocc::Point3f{}, scan, 4.0);
  CHECK(st.ray_keys > 100000);
  CHECK(all_allocations() - before == 0);
}
