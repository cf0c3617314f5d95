// The replaced global operator new of knnocc_alloc_tests (counting_new.hpp).
#include "counting_new.hpp"

#include <atomic>
#include <cstdlib>
#include <new>

#if defined(__GLIBC__)
#include <malloc.h>
#define KNNOCC_TEST_USABLE_SIZE(p) malloc_usable_size(p)
#else
#define KNNOCC_TEST_USABLE_SIZE(p) \
  std::size_t { 0 }
#endif

namespace {
std::atomic<std::size_t> g_allocations{0};
std::atomic<std::size_t> g_largest{0};
std::atomic<std::size_t> g_live{0};
std::atomic<std::size_t> g_peak{0};
}  // namespace

namespace knnocc::test {
std::size_t allocations() { return g_allocations.load(); }
std::size_t largest_allocation() { return g_largest.load(); }
void reset_largest_allocation() { g_largest.store(0); }
std::size_t live_bytes() { return g_live.load(); }
std::size_t peak_live_bytes() { return g_peak.load(); }
void reset_peak_live_bytes() { g_peak.store(g_live.load()); }
bool tracks_live_bytes() {
#if defined(__GLIBC__)
  return true;
#else
  return false;
#endif
}
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
  // single-threaded reader tests that read it.
  if (n > g_largest.load(std::memory_order_relaxed)) g_largest.store(n, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) {
    const std::size_t live = g_live += KNNOCC_TEST_USABLE_SIZE(p);
    if (live > g_peak.load(std::memory_order_relaxed))
      g_peak.store(live, std::memory_order_relaxed);
    return p;
  }
  throw std::bad_alloc();
}
KNNOCC_TEST_NOINLINE void operator delete(void* p) noexcept {
  if (p) g_live -= KNNOCC_TEST_USABLE_SIZE(p);
  std::free(p);
}
KNNOCC_TEST_NOINLINE void operator delete(void* p, std::size_t) noexcept {
  if (p) g_live -= KNNOCC_TEST_USABLE_SIZE(p);
  std::free(p);
}
