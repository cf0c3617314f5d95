// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// ScanStats: what one scan's insertion did (ScanInserter, or any scan integrator:
// insertion/scan_integrator.hpp).

#include <cstddef>

namespace knnocc {

/// What one insert_point_cloud call did.
struct ScanStats {
  std::size_t points = 0;            ///< points given
  std::size_t nonfinite = 0;         ///< skipped: NaN or Inf coordinate
  std::size_t out_of_range = 0;      ///< endpoints outside the key range (no update from them)
  std::size_t beyond_max_range = 0;  ///< points farther than max_range (truncated free ray only)
  std::size_t ray_keys = 0;          ///< voxels visited by rays, before de-duplication
  std::size_t occupied_voxels = 0;   ///< voxels that received the hit update (or a rated sum)
  std::size_t free_voxels = 0;       ///< voxels that received the miss update
  bool origin_valid = true;          ///< false: origin NaN/Inf, nothing was inserted
  /// Pieces the points were collected and walked in (0: the origin was not finite). A scan of more
  /// than ScanInserter::chunk_points (4096) points in a random-access container (not discretized,
  /// not rated) whose dense box fits goes that many points at a time, which bounds the per-point
  /// buffers; the map gets the same updates either way.
  std::size_t chunks = 0;
  /// The walk marked free voxels in a byte per voxel rather than a bit (on AVX-512 CPUs, a scan
  /// whose dense box has at most 4 M voxels and whose rays take at least 4 M steps; faster, the
  /// same map).
  bool byte_marks = false;
};

/// The scratch a ScanInserter keeps between scans, in bytes by part (ScanInserter::scratch_usage):
/// address space held; pages no scan touched are not resident, and blocks of 1 MB or more are
/// mapped and made resident 2 MB at a time (core/detail/huge_pages.hpp).
struct ScratchUsage {
  std::size_t hit_bitmaps = 0;   ///< walk, dense scratch: endpoint bits of the scan's box
  std::size_t miss_bitmaps = 0;  ///< walk, dense scratch: free-voxel bits or bytes of the box
  std::size_t point_buffers =
      0;                       ///< collect: rays and hits of the points (or of a chunk), hit codes
  std::size_t ray_blocks = 0;  ///< walk: rays set up for the bundled walk
  std::size_t hashed = 0;      ///< walk, hashed scratch: masks of the touched bricks
  std::size_t brick_groups = 0;  ///< apply: dense path's brick records; hashed order, slots
  std::size_t other = 0;         ///< apply rows, rated sums, discretized keys, chunk sums

  std::size_t total() const {
    return hit_bitmaps + miss_bitmaps + point_buffers + ray_blocks + hashed + brick_groups + other;
  }
};

}  // namespace knnocc
