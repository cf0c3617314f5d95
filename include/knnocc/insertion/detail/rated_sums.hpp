// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Eq 15's occupied term: a voxel holding endpoints of a rated scan (ScanInserter::insert_rated,
// e.g. the k-NN model) receives, once per scan, the sum of its endpoints' log-odds,
//   L(n | z_t) = sum over endpoints p in n of logit(Prob(s_p))                     (eq 15)
// summed in double in point order and rounded to float once, then applied (with clamping) in key
// order, so the map does not depend on how the points were split between threads. These voxels get
// no free update from the scan (occupied wins: brick_updates.hpp).

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "../../map/occupancy_map.hpp"
#include "thread_scratch.hpp"

namespace knnocc::detail {

/// One endpoint of a rated scan: its voxel (Key::pack), its place in point order, its log-odds.
struct RatedHit {
  std::uint64_t key;
  std::size_t order;
  float logodds;
};

/// Applies eq 15 for the hits of the first `threads` scratches' parts (consecutive points in
/// thread order); their bricks exist already (apply_updates). `sums` is scratch. Returns the
/// voxels updated.
template <class Key>
std::size_t apply_rated_hits(OccupancyMap<Key>& map, const ThreadScratches& scratch,
                             unsigned threads, std::vector<RatedHit>& sums) {
  sums.clear();
  for (unsigned t = 0; t < threads; ++t) {
    const ScanPart& part = scratch[t]->part;
    for (std::size_t j = 0; j < part.hits.size(); ++j)
      sums.push_back({part.hits[j], sums.size(), part.hit_logodds[j]});
  }
  std::sort(sums.begin(), sums.end(), [](const RatedHit& a, const RatedHit& b) {
    return a.key != b.key ? a.key < b.key : a.order < b.order;
  });
  std::size_t voxels = 0;
  for (std::size_t j = 0; j < sums.size();) {
    const std::uint64_t key = sums[j].key;
    double sum = 0.0;
    for (; j < sums.size() && sums[j].key == key; ++j) sum += sums[j].logodds;
    map.update(Key::unpack(key), static_cast<float>(sum));
    ++voxels;
  }
  return voxels;
}

}  // namespace knnocc::detail
