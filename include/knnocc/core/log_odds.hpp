// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Probability <-> log-odds (paper eq 2), with OctoMap's rounding: computed in double, stored as
// float, so logodds(0.7) == 0.847297847f exactly as in liboctomap.

#include <cmath>

namespace knnocc {

/// ln(p / (1 - p)) rounded to float.
inline float logodds(double probability) {
  return static_cast<float>(std::log(probability / (1.0 - probability)));
}

/// 1 - 1 / (1 + exp(l)).
inline double probability(double logodds_value) {
  return 1.0 - 1.0 / (1.0 + std::exp(logodds_value));
}

}  // namespace knnocc
