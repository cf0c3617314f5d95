// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// same_voxels: whether two maps hold the same known voxels with bit-identical log-odds (what
// "the same map" means for the live mapper's invariant and for the OctoMap-model equality with
// liboctomap). Storage order, brick layout and compaction do not matter.

#include <cstring>

namespace knnocc {

/// True when `a` and `b` (OccupancyMap or any map with num_voxels(), for_each_voxel(k, v) and
/// logodds(k) -> optional) know the same voxels, each with the same log-odds bit for bit.
template <class MapA, class MapB>
bool same_voxels(const MapA& a, const MapB& b) {
  if (a.num_voxels() != b.num_voxels()) return false;
  bool same = true;
  a.for_each_voxel([&](const auto& key, float v) {
    if (!same) return;
    const auto w = b.logodds(key);
    same = w && std::memcmp(&v, &*w, sizeof v) == 0;
  });
  return same;
}

}  // namespace knnocc
