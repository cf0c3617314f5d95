// insertion/detail/hashed_marks.hpp: the hashed scratch keeps its bricks in blocks; bricks are
// found again by coordinate across block boundaries, references stay valid as bricks are added,
// memory grows a block at a time, and the cap refuses the brick that would pass it. Hit masks are
// kept apart, for the bricks that hold endpoints only.

#include <doctest/doctest.h>

#include <cstdint>

#include <knnocc/core/detail/flat_index.hpp>
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
    CHECK(a.hit_of(i) == nullptr);
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

TEST_CASE("hashed_marks: hit masks only for bricks with hits, found by brick, cleared, capped") {
  HashedMarks a;
  a.at(10).miss.set(1);
  a.set_hit(10, 5);  // a brick the rays touched
  a.set_hit(20, 7);  // a new brick: added with an empty miss mask
  a.set_hit(20, 8);
  for (std::uint64_t c = 100; c < 200; ++c) a.at(c).miss.set(2);  // rays only
  REQUIRE(a.size() == 102);
  REQUIRE(a.hit_of(0) != nullptr);
  CHECK(a.hit_of(0)->test(5));
  CHECK(a.hit_of(0)->count() == 1);
  CHECK(a[0].miss.test(1));
  REQUIRE(a[1].coord == 20);
  REQUIRE(a.hit_of(1) != nullptr);
  CHECK(a.hit_of(1)->count() == 2);
  CHECK_FALSE(a[1].miss.any());
  for (std::size_t i = 2; i < a.size(); ++i) CHECK(a.hit_of(i) == nullptr);

  const std::size_t held = a.memory_usage();
  a.clear();
  CHECK(a.memory_usage() == held);  // kept for the next scan
  a.at(10);
  CHECK(a.hit_of(0) == nullptr);  // hits start empty again

  // The first hit mask is refused when it would pass the cap; the brick itself fits.
  HashedMarks b;
  b.at(1);
  b.set_cap(b.memory_usage(), 1'000'000, 42);
  CHECK_THROWS_AS(b.set_hit(1, 3), MemoryLimitError);
  CHECK(b.hit_of(0) == nullptr);
  b.set_cap(0, 0, 0);
  b.set_hit(1, 3);
  REQUIRE(b.hit_of(0) != nullptr);
  CHECK(b.hit_of(0)->test(3));
}

TEST_CASE("hashed_marks: the cap counts the map bricks the scratch will add") {
  knnocc::detail::FlatIndex map;  // a map's brick index holding bricks 0..99
  bool inserted = false;
  for (std::uint32_t c = 0; c < 100; ++c) map.find_or_insert(c, c, inserted);
  HashedMarks a;
  a.count_map_bricks(&map, 1000, 5);  // 1000 bytes a new map brick, room for 5 already
  for (std::uint64_t c = 90; c < 110; ++c) a.at(c);
  CHECK(a.size() == 20);
  CHECK(a.bricks_new_to_map() == 10);  // 100..109
  a.at(100);                           // found again: not counted twice
  CHECK(a.bricks_new_to_map() == 10);

  // Under a cap, a brick the map has fits where a new one does not: the scratch's own growth
  // is the same, but 1000 bytes more for the map (beyond the 5 spare) pass the cap.
  const std::size_t held = a.memory_usage() + 5 * 1000;  // the 10 new bricks, less 5 spare
  a.set_cap(held + 500, 1'000'000, 7);
  CHECK_NOTHROW(a.at(50));  // in the map
  CHECK(a.bricks_new_to_map() == 10);
  try {
    a.at(200);  // not in the map
    FAIL("a new map brick passed the cap");
  } catch (const MemoryLimitError& e) {
    CHECK(e.needed() >= 7 + held + 1000);
  }
  CHECK(a.bricks_new_to_map() == 10);
  a.clear();  // a new scan: nothing counted yet, the index still known
  CHECK(a.bricks_new_to_map() == 0);
  a.set_cap(0, 0, 0);
  a.at(300);
  CHECK(a.bricks_new_to_map() == 1);
  a.count_map_bricks(nullptr, 0, 0);  // not counted
  a.at(301);
  CHECK(a.bricks_new_to_map() == 1);
}
