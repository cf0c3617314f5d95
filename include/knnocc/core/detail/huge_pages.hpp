// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Large blocks of memory that a writer fills densely (the map's value slabs, a scan's ray
// buffers), mapped 2 MB at a time where the system allows it.
//
// Every fresh 4 KB page costs a page fault, and on virtual machines faults can dominate inserting
// a fresh map (a 42 MB map is 10,000 faults; bench/NOTES.md has the measured costs). On Linux a
// block of at least kHugeMin (1 MB) is rounded up to whole 2 MB pages, taken 2 MB aligned from
// mmap and advised as transparent huge pages (MADV_HUGEPAGE, honoured when THP is "always" or
// "madvise"): one fault then maps 2 MB. Smaller
// blocks, other systems, and builds with KNNOCC_NO_HUGE_PAGES defined use malloc. Only for memory
// that is filled densely: a huge page is resident as a whole once any byte of it is touched, so a
// block costs up to 2 MB more resident memory than its size. Define KNNOCC_NO_HUGE_PAGES for the
// whole program or not at all (big_alloc and big_free must agree).

#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <new>
#include <vector>

#include "../config.hpp"

#if defined(__linux__) && !defined(KNNOCC_NO_HUGE_PAGES)
#include <sys/mman.h>
#define KNNOCC_HUGE_PAGES 1
#else
#define KNNOCC_HUGE_PAGES 0
#endif

namespace knnocc::detail {

inline constexpr std::size_t kHugePage = std::size_t{2} << 20;
inline constexpr std::size_t kHugeMin = std::size_t{1} << 20;  ///< smallest block on huge pages

/// Number of big_alloc calls so far (the tests check that warmed-up writers make none).
inline std::atomic<std::size_t> big_allocations{0};

/// What a failed big_alloc leads to: std::bad_alloc, or abort() without exceptions.
[[noreturn]] inline void out_of_memory() {
#if KNNOCC_HAS_EXCEPTIONS
  throw std::bad_alloc();
#else
  std::abort();
#endif
}

/// Bytes of `bytes` rounded up the way big_alloc maps them (whole huge pages when large).
inline std::size_t big_size(std::size_t bytes) {
  if (bytes > ~std::size_t{0} - 2 * kHugePage) return bytes;  // big_alloc refuses these
  return bytes >= kHugeMin ? (bytes + kHugePage - 1) / kHugePage * kHugePage : bytes;
}

/// At least `bytes` bytes (uninitialised; zero when they come fresh from mmap), or null.
/// Release with big_free(p, bytes), the same `bytes`.
inline void* big_alloc(std::size_t bytes) {
  big_allocations.fetch_add(1, std::memory_order_relaxed);
#if KNNOCC_HUGE_PAGES
  if (bytes > ~std::size_t{0} - 2 * kHugePage) return nullptr;  // would wrap around
  if (bytes >= kHugeMin) {
    const std::size_t size = big_size(bytes);
    // Over-map by one huge page, then unmap the unaligned head and the tail.
    void* raw =
        mmap(nullptr, size + kHugePage, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (raw == MAP_FAILED) return nullptr;
    char* base = static_cast<char*>(raw);
    const std::size_t head =
        (kHugePage - reinterpret_cast<std::size_t>(base) % kHugePage) % kHugePage;
    if (head) munmap(base, head);
    munmap(base + head + size, kHugePage - head);
#if defined(MADV_HUGEPAGE)
    madvise(base + head, size, MADV_HUGEPAGE);  // advice only: ignored where THP is off
#endif
    return base + head;
  }
#endif
  return std::malloc(bytes == 0 ? 1 : bytes);
}

/// big_alloc, zero-filled (fresh mmap memory is zero already; small blocks come from calloc).
inline void* big_alloc_zeroed(std::size_t bytes) {
#if KNNOCC_HUGE_PAGES
  if (bytes >= kHugeMin) return big_alloc(bytes);
#endif
  big_allocations.fetch_add(1, std::memory_order_relaxed);
  return std::calloc(bytes == 0 ? 1 : bytes, 1);
}

inline void big_free(void* p, std::size_t bytes) {
  if (!p) return;
#if KNNOCC_HUGE_PAGES
  if (bytes >= kHugeMin) {
    munmap(p, big_size(bytes));
    return;
  }
#endif
  (void)bytes;
  std::free(p);
}

/// unique_ptr deleter for a big_alloc block of `bytes` bytes.
struct BigFree {
  std::size_t bytes = 0;
  void operator()(void* p) const { big_free(p, bytes); }
};

/// std::allocator with big_alloc: for vectors that are filled densely and may grow large.
template <class T>
struct BigAllocator {
  static_assert(alignof(T) <= alignof(std::max_align_t), "malloc's alignment is all it promises");
  using value_type = T;
  BigAllocator() = default;
  template <class U>
  BigAllocator(const BigAllocator<U>&) noexcept {}
  T* allocate(std::size_t n) {
    void* p = big_alloc(n * sizeof(T));
    if (!p) out_of_memory();
    return static_cast<T*>(p);
  }
  void deallocate(T* p, std::size_t n) noexcept { big_free(p, n * sizeof(T)); }
  template <class U>
  bool operator==(const BigAllocator<U>&) const noexcept {
    return true;
  }
  template <class U>
  bool operator!=(const BigAllocator<U>&) const noexcept {
    return false;
  }
};

/// A vector whose large buffers are mapped 2 MB at a time.
template <class T>
using BigVector = std::vector<T, BigAllocator<T>>;

}  // namespace knnocc::detail
