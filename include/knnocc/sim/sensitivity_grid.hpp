// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The sensitivity grid of the tree scene (sim/tree_scene.hpp): how wrong stereo matches look,
// swept past any one regime, so that no model can be tuned to a simulator parameter unseen:
//   patch size        {1, 2, 3, 4, 6, 8}        points per wrong patch (outlier_cluster)
//   lifetime          {0, 1, 2, 4, 6, 8, 12}    keyframes that may re-observe it (outlier_repeat)
//   re-observation    {1, 0.5}                  probability of each re-observation (repeat_prob)
// plus the mixed regime, whose every patch draws its size from 1..8 and its lifetime from 0..12
// (random_patches, re-observation probability 0.75). Every cell keeps the rest of the
// "realistic" regime (sim/regimes.hpp: the outlier rate and depth error growing with depth).
//
// Seeds: tuning and reporting never share one. A model's constants, and the oracle's choice of
// the OctoMap model's parameters, are chosen on kTuningSeeds; every figure a report prints comes
// from kReportSeeds.

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "regimes.hpp"
#include "tree_scene.hpp"

namespace knnocc::sim {

inline constexpr std::array<std::uint64_t, 5> kTuningSeeds{1, 2, 3, 4, 5};
inline constexpr std::array<std::uint64_t, 5> kReportSeeds{101, 102, 103, 104, 105};

inline constexpr std::array<std::size_t, 6> kGridPatchSizes{1, 2, 3, 4, 6, 8};
inline constexpr std::array<std::size_t, 7> kGridLifetimes{0, 1, 2, 4, 6, 8, 12};
inline constexpr std::array<double, 2> kGridProbabilities{1.0, 0.5};

struct GridCell {
  std::size_t patch = 1;     ///< points per wrong patch (the largest, when mixed)
  std::size_t lifetime = 0;  ///< keyframes that may re-observe it (the largest, when mixed)
  double probability = 1.0;  ///< probability of each re-observation
  bool mixed = false;        ///< sizes and lifetimes drawn per patch

  /// "p4 l6 r0.5", or "mixed".
  std::string name() const {
    if (mixed) return "mixed";
    char s[48];
    std::snprintf(s, sizeof s, "p%zu l%zu r%g", patch, lifetime, probability);
    return s;
  }
  /// The scene's parameters for this cell and a seed.
  TreeSceneParams params(std::uint64_t seed) const {
    Regime base;
    find_regime("realistic", base);
    TreeSceneParams p = base.params;
    p.seed = seed;
    p.outlier_cluster = patch;
    p.outlier_repeat = lifetime;
    p.repeat_prob = probability;
    p.random_patches = mixed;
    return p;
  }
};

/// The 84 cells (probability outermost, then lifetime, then patch size) and the mixed one last.
inline std::vector<GridCell> sensitivity_grid() {
  std::vector<GridCell> cells;
  for (const double r : kGridProbabilities)
    for (const std::size_t l : kGridLifetimes)
      for (const std::size_t p : kGridPatchSizes) cells.push_back({p, l, r, false});
  cells.push_back({kGridPatchSizes.back(), kGridLifetimes.back(), 0.75, true});
  return cells;
}

/// Are the two (not mixed) cells neighbours in the grid: one step along one of its three axes?
inline bool grid_neighbours(const GridCell& a, const GridCell& b) {
  if (a.mixed || b.mixed) return false;
  auto index = [](const auto& axis, auto v) {
    for (std::size_t i = 0; i < axis.size(); ++i)
      if (axis[i] == v) return static_cast<int>(i);
    return -100;
  };
  const int dp = index(kGridPatchSizes, a.patch) - index(kGridPatchSizes, b.patch);
  const int dl = index(kGridLifetimes, a.lifetime) - index(kGridLifetimes, b.lifetime);
  const int dr =
      index(kGridProbabilities, a.probability) - index(kGridProbabilities, b.probability);
  return std::abs(dp) + std::abs(dl) + std::abs(dr) == 1;
}

}  // namespace knnocc::sim
