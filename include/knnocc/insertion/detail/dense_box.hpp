// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Phase 2 of a scan (ScanInserter) starts with a choice: walk the rays into a dense scratch of the
// scan's box (a ScanBitmap per thread: fast, but its size follows the box) or into hashed per-brick
// masks (any extent, slower). plan_dense_box() makes that choice from the collected scan's key box
// and ray steps, and shapes the dense box.

#include <cstddef>
#include <cstdint>
#include <optional>

#include "../../map/brick.hpp"
#include "../../raycast/detail/fan_walk.hpp"
#include "../../raycast/detail/scan_bitmap.hpp"
#include "collect.hpp"

namespace knnocc::detail {

/// The dense scratch of a scan: a brick-aligned box of keys [lo, lo + size), and whether the walk
/// marks free voxels in bytes rather than bits.
struct DenseBox {
  std::int64_t lo[3], size[3];
  bool byte_marks = false;
};

/// Free voxels are marked in bytes, not bits, when the walk takes bundles (best_walk_path), the box
/// has at most kByteMarkVoxels voxels (a byte map of up to 4 MB per thread, taken 2 MB at a time)
/// and the scan walks at least kByteMarkSteps steps: a byte is marked by a plain store, where bits
/// of neighbouring voxels wait on each other's read-modify-writes of one word. Shorter walks gain
/// too little for the memory, and larger boxes would not fit in the caches and would multiply the
/// scratch's resident memory by eight (bench/NOTES.md has the measurements behind these limits).
inline constexpr std::int64_t kByteMarkVoxels = std::int64_t{4} << 20;
inline constexpr std::size_t kByteMarkSteps = std::size_t{4} << 20;

/// The dense box of a scan whose origin, ray ends and hits lie in `keys` and whose rays take
/// `steps` steps: the key box grown by one voxel, brick aligned, rows along x whole 64-bit words
/// (ScanBitmap::take_brick_row reads them so). nullopt when the hashed scratch should be used: the
/// box leaves the key range or exceeds kDenseMaxEdge, its two bitmaps per thread exceed
/// scratch_limit / threads bytes, or it has too many voxels for the steps. Byte marks take 9 bits
/// per voxel instead of 2 and fall back to bits when the limit is too small for bytes.
template <class Key>
std::optional<DenseBox> plan_dense_box(const KeyBox& keys, std::size_t steps,
                                       std::size_t scratch_limit, unsigned threads) {
  DenseBox box;
  std::int64_t bits = 1;
  if (!dense_box_shape<Key>(keys.lo, keys.hi, box.lo, box.size, bits)) return std::nullopt;
  // Two bitmaps per thread: occupied voxels in bits, free voxels in bytes when the box is small.
  const double limit = static_cast<double>(scratch_limit) / threads;
  box.byte_marks = best_walk_path<ByteMarks>() == WalkPath::avx512_bundles &&
                   bits <= kByteMarkVoxels && steps >= kByteMarkSteps &&
                   static_cast<double>(bits) / 8 * 9 <= limit;
  const bool fits =
      static_cast<double>(bits) / 8 * (box.byte_marks ? 9 : 2) <= limit &&
      bits <= kDenseBitsPerStep * static_cast<std::int64_t>(steps) + (std::int64_t{1} << 20);
  if (!fits) return std::nullopt;
  return box;
}

}  // namespace knnocc::detail
