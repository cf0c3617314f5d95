// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// OctoMapModel: OctoMap's inverse sensor model (paper eq 4). An endpoint's voxel gets l_occ,
// every voxel a ray crosses gets l_free; each voxel at most once per scan, occupied first.

#include <cmath>
#include <string>

#include "../core/config.hpp"
#include "../core/log_odds.hpp"

namespace knnocc {

struct OctoMapModel {
  /// Needs no k-NN statistics of the map point cloud (see Mapper).
  static constexpr bool uses_map_cloud = false;

  float hit = logodds(0.7);   ///< l_occ = 0.847297847
  float miss = logodds(0.4);  ///< l_free = -0.405465096

  /// From probabilities in (0, 1): p_hit > 0.5 marks occupied, p_miss < 0.5 marks free.
  static OctoMapModel from_probabilities(double p_hit, double p_miss) {
    if (!(p_hit > 0.5 && p_hit < 1.0))
      detail::invalid_argument("hit probability must be in (0.5, 1), got " + std::to_string(p_hit));
    if (!(p_miss > 0.0 && p_miss < 0.5))
      detail::invalid_argument("miss probability must be in (0, 0.5), got " +
                               std::to_string(p_miss));
    return OctoMapModel{logodds(p_hit), logodds(p_miss)};
  }

  float hit_logodds() const { return hit; }
  float miss_logodds() const { return miss; }
};

}  // namespace knnocc
