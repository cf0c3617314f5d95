// A warmed-up ScanInserter allocates nothing: counted with a replaced global operator new
// (which also records the largest single allocation for the IO tests).
#include <doctest/doctest.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <new>
#include <random>
#include <vector>

#include <knnocc/map/scan_inserter.hpp>

#include "test_support.hpp"

namespace {
std::atomic<std::size_t> g_allocations{0};
std::atomic<std::size_t> g_largest{0};
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
  std::vector<knnocc::Point3f> scan(20000);
  for (auto& p : scan) p = {u(rng), u(rng), u(rng) * 0.3f};

  knnocc::OccupancyMap<knnocc::OcKey> map(0.1);
  knnocc::ScanInserter<knnocc::OcKey> inserter(map);
  for (const bool discretize : {false, true}) {
    const std::size_t cold = g_allocations.load();
    inserter.insert_point_cloud(knnocc::Point3f{}, scan, -1.0, discretize);  // warm-up
    if (!discretize) CHECK(g_allocations.load() > cold);  // the counter does see allocations
    std::shuffle(scan.begin(), scan.end(), rng);
    const std::size_t before = g_allocations.load();
    const auto st = inserter.insert_point_cloud(knnocc::Point3f{}, scan, 4.0, discretize);
    const std::size_t allocations = g_allocations.load() - before;
    CAPTURE(discretize);
    CHECK(st.ray_keys > 100000);
    CHECK(allocations == 0);
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
  const std::size_t before = g_allocations.load();
  const auto st = inserter.insert_point_cloud(knnocc::Point3f{}, scan, 4.0);
  CHECK(st.ray_keys > 100000);
  CHECK(g_allocations.load() - before == 0);
}
