// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// ScanBitmap: one bit (or one byte) per voxel of a brick-aligned box of keys, the per-scan
// scratch of ScanInserter when a scan's box is small enough (see plan_dense_box,
// insertion/detail/dense_box.hpp) and of VoxelTally's see-through walk (sensor/voxel_tally.hpp).
//
// Voxel ((z - lo_z) * ny + (y - lo_y)) * nx + (x - lo_x), x fastest, so a step along an axis is a
// constant offset (what the ray walk needs). With bits, the 8 bits of a brick row (fixed y and z)
// are one byte of a 64-bit word; with bytes (a byte is 0 or 1), the 8 bytes of a brick row are one
// 64-bit word. Either way a brick's VoxelMask is its 64 rows, gathered by take_brick_row(). Bytes
// cost eight times the memory but are marked by a plain store (raycast/detail/linear_ray.hpp,
// ByteMarks).

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <new>

#include "../../core/config.hpp"
#include "../../core/detail/huge_pages.hpp"
#include "../../map/brick.hpp"

namespace knnocc::detail {

/// Bits of dense scratch per ray step at most: beyond that, clearing and scanning the bitmap would
/// cost more than walking the rays.
inline constexpr std::int64_t kDenseBitsPerStep = 64;
/// The dense box is the key box of origin and end points grown by one voxel: per axis a walk moves
/// monotonically from the origin voxel and may pass the end voxel's border by rounding (a crossing
/// computed within the length), but never a second border: that would take an error of a whole
/// voxel in t, while the float direction and length err by about 1e-6 of the ray length, under 0.2
/// voxel for the rays of a box edge below 2^16 voxels + 64 (the lane walks' precondition too).
inline constexpr std::int64_t kDenseMaxEdge = (std::int64_t{1} << 16) + 64;

/// The box [box_lo, box_lo + box_size) of a ScanBitmap for the keys lo..hi (inclusive, per axis)
/// grown by one voxel: brick aligned, rows along x whole 64-bit words (take_brick_row reads them
/// so); `voxels` its number of voxels. False when it leaves the key range or an edge exceeds
/// kDenseMaxEdge.
template <class Key>
bool dense_box_shape(const std::int64_t (&lo)[3], const std::int64_t (&hi)[3],
                     std::int64_t (&box_lo)[3], std::int64_t (&box_size)[3], std::int64_t& voxels) {
  voxels = 1;
  for (int a = 0; a < 3; ++a) {
    if (lo[a] < 1 || hi[a] > Key::extent - 2) return false;  // in key range
    box_lo[a] = (lo[a] - 1) / kBrickEdge * kBrickEdge;
    const std::int64_t end = ((hi[a] + 1) / kBrickEdge + 1) * kBrickEdge;
    const std::int64_t align = a == 0 ? 64 : kBrickEdge;
    box_size[a] = (end - box_lo[a] + align - 1) / align * align;
    if (box_size[a] > kDenseMaxEdge) return false;
    voxels *= box_size[a];
  }
  return true;
}

class ScanBitmap {
 public:
  /// From this size on a bitmap takes whole 2 MB huge pages (huge_pages.hpp), with the rest of
  /// the page as room for larger boxes. Its 32 or more fresh 4 KB pages would each cost a page
  /// fault, together more than clearing one huge page, and the boxes of a sequence grow, so
  /// smaller blocks would be reallocated and faulted in again (bench/NOTES.md has the figures).
  /// Resident memory: up to 2 MB a bitmap, two per inserter thread.
  static constexpr std::size_t kHugeBitmap = std::size_t{128} << 10;

  /// Makes this the all-zero bitmap of the box [lo, lo + size) (lo a multiple of 8, size a
  /// multiple of 64 along x and of 8 along y and z), with a bit per voxel, or a byte if
  /// `byte_per_voxel`. Keeps the memory; bits are zero already when every brick row was taken since
  /// the last use.
  void reshape(const std::int64_t (&lo)[3], const std::int64_t (&size)[3],
               bool byte_per_voxel = false) {
    if (dirty_) std::fill(bits_.get(), bits_.get() + box_words(), std::uint64_t{0});  // old box
    for (int a = 0; a < 3; ++a) {
      lo_[a] = lo[a];
      n_[a] = size[a];
    }
    bytes_ = byte_per_voxel;
    const std::size_t words = box_words();
    if (capacity_ < words) {
      // Zeroed by the kernel, not by a loop: pages no ray touches cost nothing. The box of a scan
      // is mostly crossed by its rays, so large bitmaps take huge pages (kHugeBitmap).
      bits_.reset();
      std::size_t bytes = words * sizeof(std::uint64_t);
      if (KNNOCC_HUGE_PAGES && bytes >= kHugeBitmap && bytes < kHugePage) bytes = kHugePage;
      bits_ = Bits(static_cast<std::uint64_t*>(big_alloc_zeroed(bytes)), BigFree{bytes});
      capacity_ = bits_ ? bytes / sizeof(std::uint64_t) : 0;
      if (!bits_) out_of_memory();
    }
    dirty_ = true;  // until take_brick_row has seen every row
  }

  std::int64_t index(std::int64_t x, std::int64_t y, std::int64_t z) const {
    return ((z - lo_[2]) * n_[1] + (y - lo_[1])) * n_[0] + (x - lo_[0]);
  }
  /// Index offset of one voxel along axis a.
  std::int64_t stride(int a) const { return a == 0 ? 1 : a == 1 ? n_[0] : n_[0] * n_[1]; }
  /// Bits: voxel i is bit (i & 63) of word i >> 6.
  std::uint64_t* words() { return bits_.get(); }
  /// Bytes: voxel i is byte i, 0 or 1.
  std::uint8_t* bytes() { return reinterpret_cast<std::uint8_t*>(bits_.get()); }
  bool has_bytes() const { return bytes_; }
  /// Bytes of address space held (pages no mark touched are not resident).
  std::size_t capacity_bytes() const { return capacity_ * sizeof(std::uint64_t); }

  const std::int64_t* lo() const { return lo_; }
  /// Number of bricks along axis a.
  std::int64_t bricks(int a) const { return n_[a] / kBrickEdge; }

  /// ORs the bits of the bricks (0..bricks(0)-1, by, bz) into masks[0..bricks(0)) and clears them.
  void take_brick_row(std::int64_t by, std::int64_t bz, VoxelMask* masks) {
    const std::int64_t row_words = n_[0] / (bytes_ ? 8 : 64);
    for (int lz = 0; lz < kBrickEdge; ++lz) {
      // The 8 rows (ly = 0..7) of this z slice are contiguous: skip them at once when empty.
      std::uint64_t* slice =
          bits_.get() + ((bz * kBrickEdge + lz) * n_[1] + by * kBrickEdge) * row_words;
      std::uint64_t any = 0;
      for (std::int64_t i = 0; i < kBrickEdge * row_words; ++i) any |= slice[i];
      if (!any) continue;
      for (int ly = 0; ly < kBrickEdge; ++ly) {
        std::uint64_t* row = slice + ly * row_words;
        // Row (ly, lz) of a brick is bits 8 ly .. 8 ly + 7 of VoxelMask word lz.
        const auto lz_word = static_cast<std::size_t>(lz);
        if (bytes_) {
          for (std::int64_t bx = 0; bx < row_words; ++bx) {
            const std::uint64_t w = row[bx];  // one brick's row, a byte (0 or 1) per voxel
            if (!w) continue;
            row[bx] = 0;
            masks[bx].w[lz_word] |= row_bits(w) << (8 * ly);
          }
          continue;
        }
        for (std::int64_t wx = 0; wx < row_words; ++wx) {
          const std::uint64_t w = row[wx];  // eight bricks along x, 8 bits each
          if (!w) continue;
          row[wx] = 0;
          for (int b = 0; b < 8; ++b) {
            const std::uint64_t byte = (w >> (8 * b)) & 0xff;
            masks[wx * 8 + b].w[lz_word] |= byte << (8 * ly);
          }
        }
      }
    }
  }

  /// Words per row of voxels along x.
  std::int64_t row_words() const { return n_[0] / (bytes_ ? 8 : 64); }
  /// ORs the 64 rows of the brick row (by, bz) into acc[0..row_words()), leaving the bits: then
  /// brick bx has a bit set iff brick_in(acc, bx).
  void or_brick_row(std::int64_t by, std::int64_t bz, std::uint64_t* acc) const {
    const std::int64_t words = row_words();
    for (int lz = 0; lz < kBrickEdge; ++lz) {
      const std::uint64_t* row =
          bits_.get() + ((bz * kBrickEdge + lz) * n_[1] + by * kBrickEdge) * words;
      for (int ly = 0; ly < kBrickEdge; ++ly, row += words)
        for (std::int64_t w = 0; w < words; ++w) acc[w] |= row[w];
    }
  }
  bool brick_in(const std::uint64_t* acc, std::int64_t bx) const {
    return bytes_ ? acc[bx] != 0 : ((acc[bx >> 3] >> (8 * (bx & 7))) & 0xff) != 0;
  }
  /// Makes brick_in(acc, bx) true.
  void add_brick(std::uint64_t* acc, std::int64_t bx) const {
    if (bytes_)
      acc[bx] |= 1;
    else
      acc[bx >> 3] |= std::uint64_t{1} << (8 * (bx & 7));
  }
  /// The bricks bx with brick_in(acc, bx).
  std::size_t bricks_in(const std::uint64_t* acc) const {
    std::size_t n = 0;
    for (std::int64_t i = 0; i < row_words(); ++i) {
      std::uint64_t w = acc[i];
      if (bytes_) {
        n += w != 0;
        continue;
      }
      w |= w >> 4;  // bit 8 b of w: whether byte b has a bit set
      w |= w >> 2;
      w |= w >> 1;
      n += static_cast<std::size_t>(popcount64(w & 0x0101010101010101ull));
    }
    return n;
  }

  /// The 8 bytes of w, each 0 or 1, as 8 bits (byte k to bit k). Byte k times 2^(7 (8 - k)) lands
  /// on bit 56 + k; no two of the 64 partial products share a bit, so nothing carries.
  static std::uint64_t row_bits(std::uint64_t w) { return (w * 0x0102040810204080ull) >> 56; }
  /// Call after taking every brick row: the bitmap is all zero again.
  void mark_clean() { dirty_ = false; }

 private:
  std::size_t box_words() const {
    return static_cast<std::size_t>(n_[0] / (bytes_ ? 8 : 64) * n_[1] * n_[2]);
  }

  using Bits = std::unique_ptr<std::uint64_t[], BigFree>;
  Bits bits_;
  std::size_t capacity_ = 0;  // words
  std::int64_t lo_[3] = {0, 0, 0};
  std::int64_t n_[3] = {0, 0, 0};
  bool dirty_ = false;
  bool bytes_ = false;
};

}  // namespace knnocc::detail
