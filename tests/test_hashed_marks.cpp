// insertion/detail/hashed_marks.hpp: the hashed scratch keeps its bricks in blocks; bricks are
// found again by coordinate across block boundaries, references stay valid as bricks are added,
// memory grows a block at a time, and the cap refuses the brick that would pass it.

#include <doctest/doctest.h>

#include <cstdint>

#include <knnocc/core/memory_limit.hpp>
#include <knnocc/insertion/detail/hashed_marks.hpp>

using knnocc::MemoryLimitError;
using knnocc::detail::BrickMasks;
using knnocc::detail::HashedMarks;

TEST_CASE("hashed_marks: bricks over several blocks, found again, merged, cleared") {
  constexpr std::size_t block = HashedMarks::kBlock;
  const std::size_t n = 3 * block + 5;
  HashedMarks a;
  for (std::size_t i = 0; i < n; ++i) a.at(i * 7 + 1).miss.set(static_cast<int>(i % 512));
  REQUIRE(a.size() == n);
  const BrickMasks* first = &a.at(1);
  for (std::size_t i = 0; i < n; ++i) {
    CHECK(a[i].coord == i * 7 + 1);
    CHECK(a[i].miss.test(static_cast<int>(i % 512)));
    CHECK(a[i].miss.count() == 1);
    CHECK_FALSE(a[i].hit.any());
    CHECK(&a.at(i * 7 + 1) == &a[i]);  // found by coordinate
  }
  for (std::size_t i = 0; i < block; ++i) a.at(1'000'000 + i);  // another block
  CHECK(&a.at(1) == first);                                     // earlier bricks stay put
  const std::size_t blocks = (a.size() + block - 1) / block;
  CHECK(a.memory_usage() >= blocks * block * sizeof(BrickMasks));
  CHECK(a.memory_usage() < (blocks + 1) * block * sizeof(BrickMasks) + 64 * a.size());

  HashedMarks b;
  b.at(1).miss.set(3);
  b.at(5'000'000).miss.set(4);
  const std::size_t before = a.size();
  a.merge_misses(b);
  CHECK(a.size() == before + 1);
  CHECK(a.at(1).miss.test(3));
  CHECK(a.at(1).miss.test(0));
  CHECK(a.at(5'000'000).miss.test(4));

  const std::size_t held = a.memory_usage();
  a.clear();
  CHECK(a.size() == 0);
  CHECK(a.memory_usage() == held);  // kept for the next scan
  CHECK_FALSE(a.at(1).miss.any());  // a brick added again starts empty
}

TEST_CASE("hashed_marks: the cap refuses the brick that would pass it, not those it has") {
  HashedMarks a;
  for (std::uint64_t c = 0; c < HashedMarks::kBlock; ++c) a.at(c);  // one full block
  const std::size_t held = a.memory_usage();
  a.set_cap(held + 1, 10 * held, 123);  // no room for another block
  CHECK_NOTHROW(a.at(5));               // found, not added
  try {
    a.at(HashedMarks::kBlock + 7);
    FAIL("a new brick passed the cap");
  } catch (const MemoryLimitError& e) {
    CHECK(e.limit() == 10 * held);
    // what the scratch would hold with the next block, plus what the limit counts elsewhere
    CHECK(e.needed() >= 123 + held + HashedMarks::kBlock * sizeof(BrickMasks));
  }
  CHECK(a.size() == HashedMarks::kBlock);
  CHECK(a.memory_usage() == held);
  a.set_cap(0, 0, 0);  // no cap
  CHECK_NOTHROW(a.at(HashedMarks::kBlock + 7));
  CHECK(a.size() == HashedMarks::kBlock + 1);
}
