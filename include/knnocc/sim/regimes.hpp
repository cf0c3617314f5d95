// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Named outlier regimes of the tree scene (sim/tree_scene.hpp), run by `knnocc demo` and
// bench/bench_robust_model.cpp:
//   isolated    the paper-like default: isolated wrong matches, each seen by one keyframe
//   clustered   each wrong match a patch of 6 features within ~3 cm sharing its depth error
//   repeated    clustered, and every patch re-observed by the next 4 keyframes that see it
//   realistic   clustered and repeated (each re-observation with probability 0.75), the outlier
//               rate and depth error growing with depth (gain 1), 3 % wrong points, features of
//               unequal strength (detect 0.6, detect_spread 0.8): calibrated on how the real
//               stereo keyframes' map points are observed (`knnocc eval --ids
//               ../shared/data/orbslam2_stereo_keyframes --crop 4`: views per point, observation
//               span, detection rate; docs/evaluation.md has real against simulated)

#include <string>
#include <vector>

#include "tree_scene.hpp"

namespace knnocc::sim {

struct Regime {
  std::string name;
  TreeSceneParams params;  ///< seed left at its default
};

inline std::vector<Regime> named_regimes() {
  std::vector<Regime> r(4);
  r[0].name = "isolated";
  r[1].name = "clustered";
  r[1].params.outlier_cluster = 6;
  r[2].name = "repeated";
  r[2].params.outlier_cluster = 6;
  r[2].params.outlier_repeat = 4;
  r[3].name = "realistic";
  r[3].params.outlier_cluster = 6;
  r[3].params.outlier_repeat = 4;
  r[3].params.repeat_prob = 0.75;
  r[3].params.outlier_depth_gain = 1.0;
  r[3].params.outliers = 0.03;
  r[3].params.detect = 0.6;
  r[3].params.detect_spread = 0.8;
  return r;
}

/// The regime of that name; false when there is none.
inline bool find_regime(const std::string& name, Regime& out) {
  for (const Regime& r : named_regimes())
    if (r.name == name) {
      out = r;
      return true;
    }
  return false;
}

}  // namespace knnocc::sim
