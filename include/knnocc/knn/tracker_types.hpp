// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The plain types of the k-NN tracker (knn/tracker.hpp): its parameters and what one update did.
// They need no KD-tree, so the sensor models and the mapper can name them without nanoflann.

#include <cstddef>
#include <limits>

#include "../core/config.hpp"

namespace knnocc {

/// The one default k (neighbours per map point) of the tracker and the k-NN model. The paper does
/// not give its k; 8 is the best of the documented sweep over k, w, P_u and P_w on the simulated
/// tree scene (bench/bench_knn_sweep.cpp: fewest irrelevant nodes among the settings that keep
/// >= 97 % of the OctoMap model's nodes in the reference shell).
inline constexpr std::size_t kDefaultK = 8;

struct TrackerParams {
  std::size_t k = kDefaultK;                                 ///< neighbours per point
  double s_limit = std::numeric_limits<double>::infinity();  ///< valid iff s < s_limit
  std::size_t compact_min_dead = 4096;  ///< compact when dead entries exceed this and live ones
  std::size_t rebuild_min = 4096;       ///< see PointIndex: when the static KD-tree is rebuilt

  void validate() const {
    if (k < 1 || k > 4096) detail::invalid_argument("k must be in [1, 4096]");
    if (rebuild_min < 1 || rebuild_min > (std::size_t{1} << 29))
      detail::invalid_argument("rebuild_min must be in [1, 2^29]");
    if (!(s_limit > 0.0)) detail::invalid_argument("s_limit must be > 0");
  }
};

/// What one apply() did.
struct TrackerUpdate {
  std::size_t added = 0;     ///< new points (moved ones not included)
  std::size_t removed = 0;   ///< disappeared points
  std::size_t moved = 0;     ///< points with a new position
  std::size_t affected = 0;  ///< existing points whose k-NN set changed
  std::size_t skipped_nonfinite = 0;
};

}  // namespace knnocc
