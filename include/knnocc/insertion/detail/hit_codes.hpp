// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// HitCodes: a chunked scan's hits as 32-bit codes in brick-row order, in place of a hit bitmap of
// the scan's box when the scan has few points for its box (the one-thread apply reads them).
//
// A hit bitmap costs a bit per voxel of the box, mapped 2 MB at a time (ScanBitmap); a code costs
// 4 bytes per hit. A code is the voxel's brick row (bz, by) of the box, its brick bx in the row
// (bx_bits wide) and its index in the brick (local_of order, 9 bits): sorting the codes by brick
// row (by_row: a counting sort) hands the apply each row's hits, which it ORs into the
// row's masks, with shifts only. The collector stores a hit only when its code differs from the
// previous hit's (neighbouring points often share a voxel).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "../../map/brick.hpp"

namespace knnocc::detail {

class HitCodes {
 public:
  /// Codes of the box [lo, lo + size) (brick aligned); false when its codes would not fit in 32
  /// bits below ~0 (the scan keeps its hit bitmap then).
  bool shape(const std::int64_t (&lo)[3], const std::int64_t (&size)[3]) {
    for (int a = 0; a < 3; ++a) {
      lo_[a] = lo[a];
      bricks_[a] = size[a] / kBrickEdge;
    }
    bx_bits_ = 0;
    while ((std::int64_t{1} << bx_bits_) < bricks_[0]) ++bx_bits_;
    rows_ = bricks_[1] * bricks_[2];
    return bx_bits_ + kBrickBits * 3 < 32 &&
           rows_ < (std::int64_t{1} << (32 - bx_bits_ - 3 * kBrickBits));
  }

  /// The code of key k (in the box).
  std::uint32_t code(const std::int64_t (&k)[3]) const {
    const std::int64_t x = k[0] - lo_[0], y = k[1] - lo_[1], z = k[2] - lo_[2];
    constexpr std::int64_t m = kBrickEdge - 1;
    const std::int64_t row = (z >> kBrickBits) * bricks_[1] + (y >> kBrickBits);
    const std::int64_t local = (x & m) | ((y & m) << kBrickBits) | ((z & m) << (2 * kBrickBits));
    return static_cast<std::uint32_t>((((row << bx_bits_) | (x >> kBrickBits)) << 9) | local);
  }
  std::size_t row_of(std::uint32_t c) const { return c >> (bx_bits_ + 3 * kBrickBits); }
  std::size_t brick_of(std::uint32_t c) const {
    return (c >> (3 * kBrickBits)) & ((std::uint32_t{1} << bx_bits_) - 1);
  }
  static int local_of(std::uint32_t c) { return static_cast<int>(c & (kBrickVoxels - 1)); }

  /// Writes codes[0, n) to out[0, n) sorted by brick row (a counting sort: one pass that streams
  /// the codes, where sorting in place chains dependent random accesses); afterwards row r's
  /// codes are out[row_start(r), row_start(r + 1)).
  void by_row(const std::uint32_t* codes, std::size_t n, std::uint32_t* out) {
    const auto rows = static_cast<std::size_t>(rows_);
    start_.assign(rows + 1, 0);
    for (std::size_t i = 0; i < n; ++i) ++start_[row_of(codes[i]) + 1];
    for (std::size_t r = 0; r < rows; ++r) start_[r + 1] += start_[r];
    next_.assign(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < n; ++i) out[next_[row_of(codes[i])]++] = codes[i];
  }
  std::size_t row_start(std::size_t r) const { return start_[r]; }
  /// f(brick bx in the row, index in the brick) for each of brick row r's codes (after by_row).
  template <class F>
  void for_row(const std::uint32_t* codes, std::size_t r, F&& f) const {
    for (std::size_t j = start_[r], e = start_[r + 1]; j < e; ++j)
      f(brick_of(codes[j]), local_of(codes[j]));
  }

  std::size_t memory_usage() const {
    return (start_.capacity() + next_.capacity()) * sizeof(std::size_t);
  }

 private:
  std::int64_t lo_[3] = {0, 0, 0}, bricks_[3] = {0, 0, 0};
  std::int64_t rows_ = 0;
  int bx_bits_ = 0;
  std::vector<std::size_t> start_, next_;  // by_row: each row's first code, and the next free one
};

}  // namespace knnocc::detail
