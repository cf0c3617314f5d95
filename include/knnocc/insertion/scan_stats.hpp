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

}  // namespace knnocc
