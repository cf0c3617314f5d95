// HitCodes (insertion/detail/hit_codes.hpp) against direct brick arithmetic and std::sort.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <tuple>
#include <vector>

#include <knnocc/insertion/detail/hit_codes.hpp>

#include "test_support.hpp"

TEST_CASE("insert.hit_codes_give_each_brick_row_its_hits") {
  // Random keys of a brick-aligned box (with repeats): every code names the key's brick row, its
  // brick in the row and its voxel in the brick; by_row() sorts the codes by brick row into a
  // second array (the same multiset, each row's codes where row_start() says, in list order).
  using knnocc::detail::HitCodes;
  knnocc::test::Rng rng(29);
  const std::int64_t lo[3] = {64, 8, 1024};
  for (const auto& size : {std::vector<std::int64_t>{64, 8, 8}, {128, 48, 40}, {576, 520, 64}}) {
    const std::int64_t sz[3] = {size[0], size[1], size[2]};
    CAPTURE(sz[0]);
    HitCodes codes;
    REQUIRE(codes.shape(lo, sz));
    std::uniform_int_distribution<std::int64_t> x(0, sz[0] - 1), y(0, sz[1] - 1), z(0, sz[2] - 1);
    std::vector<std::uint32_t> list;
    std::vector<std::tuple<std::size_t, std::size_t, int>> want;  // row, brick, local
    for (int i = 0; i < 20000; ++i) {
      const std::int64_t k[3] = {lo[0] + x(rng), lo[1] + y(rng), lo[2] + z(rng)};
      const std::int64_t d[3] = {k[0] - lo[0], k[1] - lo[1], k[2] - lo[2]};
      const auto row = static_cast<std::size_t>((d[2] / 8) * (sz[1] / 8) + d[1] / 8);
      const auto brick = static_cast<std::size_t>(d[0] / 8);
      const int local = static_cast<int>(d[0] % 8 + 8 * (d[1] % 8) + 64 * (d[2] % 8));
      const std::uint32_t c = codes.code(k);
      CHECK(codes.row_of(c) == row);
      CHECK(codes.brick_of(c) == brick);
      CHECK(HitCodes::local_of(c) == local);
      list.push_back(c);
      if (i % 5 == 0) list.push_back(c);  // repeats
    }
    std::vector<std::uint32_t> rows_of(list.size());
    codes.by_row(list.data(), list.size(), rows_of.data());
    const std::size_t rows = static_cast<std::size_t>(sz[1] / 8 * (sz[2] / 8));
    CHECK(codes.row_start(0) == 0);
    CHECK(codes.row_start(rows) == list.size());
    for (std::size_t r = 0; r < rows; ++r)
      for (std::size_t j = codes.row_start(r); j < codes.row_start(r + 1); ++j)
        CHECK(codes.row_of(rows_of[j]) == r);
    // The same multiset, and stable: within a row, the codes keep their order in the list.
    std::vector<std::uint32_t> stable;
    for (std::size_t r = 0; r < rows; ++r)
      for (std::uint32_t c : list)
        if (codes.row_of(c) == r) stable.push_back(c);
    CHECK(rows_of == stable);
  }
  // A box whose codes would pass 32 bits is refused (its scan keeps the hit bitmap).
  HitCodes codes;
  const std::int64_t huge[3] = {std::int64_t{1} << 14, std::int64_t{1} << 12,
                                std::int64_t{1} << 10};
  CHECK_FALSE(codes.shape(lo, huge));
}
