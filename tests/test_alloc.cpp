// A warmed-up ScanInserter allocates nothing: counted with a replaced global operator new
// (which also records the largest single allocation for the IO tests) and the library's own
// counter of large blocks (detail::big_allocations).
#include <doctest/doctest.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <new>
#include <random>
#include <vector>

#include <knnocc/core/detail/huge_pages.hpp>
#include <knnocc/insertion/scan_inserter.hpp>

#include "test_support.hpp"

namespace {
std::atomic<std::size_t> g_allocations{0};
std::atomic<std::size_t> g_largest{0};
// operator new and the library's large blocks (maps' value slabs, scan scratch: huge_pages.hpp).
std::size_t all_allocations() {
  return g_allocations.load() + knnocc::detail::big_allocations.load();
}
}  // namespace

namespace knnocc::test {
// Declared in test_support.hpp: lets the IO tests check that a lying header is never believed.
std::size_t largest_allocation() { return g_largest.load(); }
void reset_largest_allocation() { g_largest.store(0); }
}  // namespace knnocc::test

// Not inlined: GCC 12 would otherwise pair the inlined malloc of one with the free of the other
// (-Wmismatched-new-delete) wherever a container's new and delete meet in one function.
#if defined(__GNUC__)
#define KNNOCC_TEST_NOINLINE __attribute__((noinline))
#else
#define KNNOCC_TEST_NOINLINE
#endif

KNNOCC_TEST_NOINLINE void* operator new(std::size_t n) {
  ++g_allocations;
  // Racy max (another thread may store a smaller value in between): exact for the
  // single-threaded IO tests that read it.
  if (n > g_largest.load(std::memory_order_relaxed)) g_largest.store(n, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
KNNOCC_TEST_NOINLINE void operator delete(void* p) noexcept { std::free(p); }
KNNOCC_TEST_NOINLINE void operator delete(void* p, std::size_t) noexcept { std::free(p); }

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
      const std::size_t cold = g_allocations.load(), cold_big = knnocc::detail::big_allocations;
      inserter.insert_point_cloud(knnocc::Point3f{}, scan, -1.0, discretize);  // warm-up
      if (!discretize) {  // the counters do see allocations
        CHECK(g_allocations.load() > cold);
        CHECK(knnocc::detail::big_allocations > cold_big);
      }
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
  std::shuffle(scan.begin(), scan.end(), rng);
  const std::size_t before = all_allocations();
  const auto st = inserter.insert_point_cloud(knnocc::Point3f{}, scan, 4.0);
  CHECK(st.ray_keys > 100000);
  CHECK(all_allocations() - before == 0);
}
