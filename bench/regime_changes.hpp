#pragma once
// A named regime's scene with the wrong patches changed by bench_robust_model's and
// diag_robust_model's --repeat N (re-observed by the next N keyframes), --cluster N (N features
// per patch) and --repeat-prob P (each re-observation with probability P); negative: the regime's
// own. Only regimes that have repeated or clustered patches change.

#include <cstddef>
#include <cstdint>

#include <knnocc/sim/regimes.hpp>
#include <knnocc/sim/tree_scene.hpp>

namespace knnocc::bench {

struct RegimeChanges {
  int repeat = -1;
  int cluster = -1;
  double repeat_prob = -1;
};

inline sim::TreeSceneParams changed_params(const sim::Regime& regime, int seed,
                                           const RegimeChanges& c) {
  sim::TreeSceneParams p = regime.params;
  p.seed = static_cast<std::uint64_t>(seed);
  if (c.repeat >= 0 && p.outlier_repeat > 0) p.outlier_repeat = static_cast<std::size_t>(c.repeat);
  if (c.cluster >= 1 && p.outlier_cluster > 1)
    p.outlier_cluster = static_cast<std::size_t>(c.cluster);
  if (c.repeat_prob >= 0 && p.outlier_repeat > 0) p.repeat_prob = c.repeat_prob;
  return p;
}

}  // namespace knnocc::bench
