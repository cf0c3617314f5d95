// ScanBitmap (raycast/detail/scan_bitmap.hpp): the dense per-scan scratch.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <list>
#include <map>
#include <set>
#include <vector>

#include <knnocc/insertion/scan_inserter.hpp>

#include "test_support.hpp"

using knnocc::OccupancyMap;
using knnocc::OcKey;
using knnocc::Point3f;
using knnocc::WideKey;

TEST_CASE("insert.scan_bitmap_grows_in_place_and_comes_back_zero") {
  // ScanBitmap, the dense scratch: a box from kHugeBitmap on takes whole huge pages, so the
  // growing boxes of a sequence (TUM at 0.05 m: 91 KB to 364 KB) reuse one block; and a bitmap
  // left dirty (rows never taken) is all zero again after the next reshape, whatever its box.
  using knnocc::detail::ScanBitmap;
  const auto words_of = [](const std::int64_t(&size)[3]) {
    return static_cast<std::size_t>(size[0] / 64 * size[1] * size[2]);
  };
  const std::int64_t lo[3] = {64, 8, 16};
  const std::int64_t small[3] = {64, 64, 64};     // 32 KB
  const std::int64_t medium[3] = {128, 64, 128};  // 128 KB: from here on huge pages
  const std::int64_t large[3] = {256, 128, 96};   // 384 KB
  ScanBitmap bitmap;
  bitmap.reshape(lo, small);
  const auto set_all_over = [&](const std::int64_t(&size)[3]) {
    for (std::int64_t z = 0; z < size[2]; z += 7)
      for (std::int64_t y = 0; y < size[1]; y += 5)
        for (std::int64_t x = 0; x < size[0]; x += 3)
          knnocc::detail::set_bit(bitmap.words(), bitmap.index(lo[0] + x, lo[1] + y, lo[2] + z));
  };
  const auto all_zero = [&](const std::int64_t(&size)[3]) {
    const std::uint64_t* w = bitmap.words();
    return std::all_of(w, w + words_of(size), [](std::uint64_t v) { return v == 0; });
  };
  set_all_over(small);  // left dirty
  bitmap.reshape(lo, medium);
  CHECK(all_zero(medium));
  const std::uint64_t* block = bitmap.words();
  set_all_over(medium);  // dirty again, then a smaller box and a larger one
  bitmap.reshape(lo, small);
  CHECK(all_zero(small));
  set_all_over(small);
  const std::size_t before = knnocc::detail::big_allocations;
  bitmap.reshape(lo, large);
  CHECK(all_zero(large));
  if (KNNOCC_HUGE_PAGES) {  // the 128 KB box took a whole huge page, room for the 384 KB one
    CHECK(bitmap.words() == block);
    CHECK(knnocc::detail::big_allocations == before);
  }
}

TEST_CASE("insert.scan_bitmap_bytes_read_back_as_bricks") {
  // A ScanBitmap with a byte per voxel: every 8-byte brick row converts to its 8 bits
  // (row_bits, all 256 patterns), take_brick_row gives the bricks' masks as with bits and leaves
  // the bytes zero, and switching a dirty byte map back to bits (or a dirty bitmap to bytes)
  // clears the old box in its own unit.
  using knnocc::detail::ScanBitmap;
  for (unsigned pattern = 0; pattern < 256; ++pattern) {
    std::uint64_t w = 0;
    for (int b = 0; b < 8; ++b)
      if ((pattern >> b) & 1u) w |= std::uint64_t{1} << (8 * b);
    CHECK(ScanBitmap::row_bits(w) == pattern);
  }
  const std::int64_t lo[3] = {64, 8, 16}, size[3] = {128, 16, 24};
  knnocc::test::Rng rng(5);
  std::uniform_int_distribution<std::int64_t> x(0, size[0] - 1), y(0, size[1] - 1),
      z(0, size[2] - 1);
  ScanBitmap bytes, bits;
  bytes.reshape(lo, size, true);
  bits.reshape(lo, size);
  REQUIRE(bytes.has_bytes());
  REQUIRE_FALSE(bits.has_bytes());
  for (int i = 0; i < 3000; ++i) {
    const std::int64_t k[3] = {lo[0] + x(rng), lo[1] + y(rng), lo[2] + z(rng)};
    bytes.bytes()[bytes.index(k[0], k[1], k[2])] = 1;
    knnocc::detail::set_bit(bits.words(), bits.index(k[0], k[1], k[2]));
  }
  const auto n = static_cast<std::size_t>(bits.bricks(0));
  std::vector<knnocc::VoxelMask> from_bytes(n), from_bits(n);
  std::size_t differing = 0, set = 0;
  for (std::int64_t bz = 0; bz < bits.bricks(2); ++bz)
    for (std::int64_t by = 0; by < bits.bricks(1); ++by) {
      for (std::size_t b = 0; b < n; ++b) from_bytes[b].clear(), from_bits[b].clear();
      bytes.take_brick_row(by, bz, from_bytes.data());
      bits.take_brick_row(by, bz, from_bits.data());
      for (std::size_t b = 0; b < n; ++b) {
        differing += from_bytes[b].w != from_bits[b].w;
        set += static_cast<std::size_t>(from_bits[b].count());
      }
    }
  CHECK(differing == 0);
  CHECK(set > 2500);  // 3000 draws, some of them the same voxel
  const std::uint8_t* b8 = bytes.bytes();
  CHECK(std::all_of(b8, b8 + size[0] * size[1] * size[2], [](std::uint8_t v) { return v == 0; }));
  // Dirty in bytes, then bits over a box of a different shape; and back.
  bytes.bytes()[bytes.index(lo[0] + size[0] - 1, lo[1] + size[1] - 1, lo[2] + size[2] - 1)] = 1;
  const std::int64_t other[3] = {64, 64, 64};
  bytes.reshape(lo, other);
  const std::uint64_t* w = bytes.words();
  CHECK(std::all_of(w, w + 64 * 64, [](std::uint64_t v) { return v == 0; }));
  knnocc::detail::set_bit(bytes.words(), bytes.index(lo[0] + 63, lo[1] + 63, lo[2] + 63));
  bytes.reshape(lo, size, true);
  CHECK(std::all_of(bytes.bytes(), bytes.bytes() + size[0] * size[1] * size[2],
                    [](std::uint8_t v) { return v == 0; }));
}
