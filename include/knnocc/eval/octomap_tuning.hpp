// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The OctoMap model at its best, as the authors' 2022 paper compares against it: the hit / miss /
// occupancy-threshold setting with the best F1 of their counting (eval/confusion.hpp) against a
// reference, over a grid like theirs. The reference picks the setting: an oracle baseline, which
// no user without ground truth can reproduce; every place that prints it says so.
//
//   hit        {0.55, 0.6, 0.7, 0.8, 0.9, 0.97}
//   miss       {0.05, 0.1, 0.2, 0.3, 0.4, 0.45, 0.49}
//   threshold  {0.5, 0.6, 0.7, 0.8, 0.9}
//
// tune_octomap(counts) calls counts(hit, miss, thresholds) once per hit/miss pair; it maps
// whatever the caller's data is with OctoMapModel::from_probabilities(hit, miss) and returns one
// ConfusionCounts per threshold (the log-odds of tuning_thresholds(), in order; e.g. summed over
// several seeds, count_confusion(map, ref, thresholds)). The evaluation knows nothing of Mapper.
//
// Thread safety: functions of their arguments only.

#include <cstddef>
#include <vector>

#include "../core/log_odds.hpp"
#include "confusion.hpp"

namespace knnocc::eval {

inline const std::vector<double>& tuning_hits() {
  static const std::vector<double> v{0.55, 0.6, 0.7, 0.8, 0.9, 0.97};
  return v;
}
inline const std::vector<double>& tuning_misses() {
  static const std::vector<double> v{0.05, 0.1, 0.2, 0.3, 0.4, 0.45, 0.49};
  return v;
}
inline const std::vector<double>& tuning_thresholds() {
  static const std::vector<double> v{0.5, 0.6, 0.7, 0.8, 0.9};
  return v;
}

/// One setting of the OctoMap model and what the counting gave it.
struct OctoMapSetting {
  double hit = 0.7, miss = 0.4, threshold = 0.5;  ///< probabilities (OctoMap's defaults)
  ConfusionCounts counts;
};

/// Every setting of the grid with its counts, in grid order (hit, then miss, then threshold);
/// best_setting() picks the oracle's.
template <class Count>
std::vector<OctoMapSetting> tune_octomap(Count&& counts) {
  std::vector<float> thresholds;
  for (const double t : tuning_thresholds()) thresholds.push_back(logodds(t));
  std::vector<OctoMapSetting> out;
  for (const double h : tuning_hits())
    for (const double m : tuning_misses()) {
      const std::vector<ConfusionCounts> c = counts(h, m, thresholds);
      for (std::size_t t = 0; t < thresholds.size() && t < c.size(); ++t)
        out.push_back({h, m, tuning_thresholds()[t], c[t]});
    }
  return out;
}

/// The setting with the best F1 (the first in grid order among equals); OctoMap's defaults with
/// empty counts when `settings` is empty.
inline OctoMapSetting best_setting(const std::vector<OctoMapSetting>& settings) {
  OctoMapSetting best;
  bool any = false;
  for (const OctoMapSetting& s : settings)
    if (!any || s.counts.f1() > best.counts.f1()) {
      best = s;
      any = true;
    }
  return best;
}

}  // namespace knnocc::eval
