// Large blocks (core/detail/huge_pages.hpp): big_alloc and BigVector.
#include <doctest/doctest.h>

#include <cstdint>
#include <set>
#include <vector>

#include <knnocc/map/value_pool.hpp>

using knnocc::OcKey;

TEST_CASE("memory.big_alloc_small_and_large_blocks") {
  for (const std::size_t bytes :
       {std::size_t{1}, std::size_t{4096}, knnocc::detail::kHugeMin - 8, knnocc::detail::kHugeMin,
        knnocc::detail::kHugePage, 3 * knnocc::detail::kHugePage + 1}) {
    CAPTURE(bytes);
    auto* p = static_cast<unsigned char*>(knnocc::detail::big_alloc_zeroed(bytes));
    REQUIRE(p != nullptr);
    bool zero = true;
    for (std::size_t i = 0; i < bytes; i += 1024) zero = zero && p[i] == 0;
    CHECK(zero);
    CHECK(p[bytes - 1] == 0);
    p[0] = 1;
    p[bytes - 1] = 2;  // the whole block is writable
#if KNNOCC_HUGE_PAGES
    if (bytes >= knnocc::detail::kHugeMin)  // whole huge pages, 2 MB aligned
      CHECK(reinterpret_cast<std::uintptr_t>(p) % knnocc::detail::kHugePage == 0);
#endif
    CHECK(knnocc::detail::big_size(bytes) >= bytes);
    knnocc::detail::big_free(p, bytes);
  }
  knnocc::detail::big_free(nullptr, 10);  // no-op
}

TEST_CASE("memory.big_vector_grows_through_the_huge_page_size") {
  knnocc::detail::BigVector<std::uint64_t> v;
  const std::size_t n = 3 * knnocc::detail::kHugePage / sizeof(std::uint64_t);
  for (std::size_t i = 0; i < n; ++i) v.push_back(i * 3);
  bool same = true;
  for (std::size_t i = 0; i < n; ++i) same = same && v[i] == i * 3;
  CHECK(same);
  v.clear();
  v.shrink_to_fit();
  CHECK(v.capacity() == 0);
}
