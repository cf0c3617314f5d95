// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// ThreadScratch: what one of ScanInserter's threads keeps between scans, so that a warmed-up
// inserter allocates nothing per scan: its share of the collected points (phase 1), its dense
// bitmaps or hashed masks and its ray block (phase 2), its buffers and counts for the apply
// (phase 3). Each thread's scratch is a separate allocation, so threads share no cache lines.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "../../map/brick.hpp"
#include "../../raycast/detail/ray_block.hpp"
#include "../../raycast/detail/scan_bitmap.hpp"
#include "append_buffer.hpp"
#include "collect.hpp"
#include "hashed_marks.hpp"
#include "hit_codes.hpp"

namespace knnocc::detail {

/// What one thread's share of the apply did.
struct UpdateCounts {
  std::size_t occupied = 0, free = 0, added = 0;
};

struct ThreadScratch {
  ScanPart part;                         // collect: this thread's share of the points
  std::vector<RayEnd> crossing;          // collect, clipped scans: rays that cross the clip
  PointBounds bounds;                    // collect, chunked scans: the bounds of its share
  ScanBitmap hit, miss;                  // walk, dense scratch: endpoints and free voxels
  AppendBuffer<std::uint32_t> hit_list;  // collect, chunked scans with few points: hit codes
  HitCodes hit_codes;                    // their encoding, and their order by brick row
  AppendBuffer<std::uint32_t> hit_rows;  // apply: hit_list sorted by brick row
  HashedMarks hashed;                    // walk, hashed scratch
  std::unique_ptr<RayBlock> block = std::make_unique<RayBlock>();  // walk: rays set up
  std::size_t visits = 0;                                          // walk: voxels visited
  std::vector<VoxelMask> row_hit, row_miss;  // apply: one row of bricks of the dense scratch
  std::vector<std::uint64_t> row_any;        // apply, fresh map: which bricks of a row are touched
  UpdateCounts counts;                       // apply
};

using ThreadScratches = std::vector<std::unique_ptr<ThreadScratch>>;

}  // namespace knnocc::detail
