// The OctoMap oracle's search (eval/octomap_tuning.hpp): every setting of the grid is counted once
// per hit/miss pair, in grid order, and the best F1 (the first among equals) is chosen.

#include <doctest/doctest.h>

#include <cmath>
#include <vector>

#include <knnocc/eval/octomap_tuning.hpp>

using namespace knnocc;

TEST_CASE("octomap_tuning: every setting once, the best F1 chosen, the first among equals") {
  std::size_t calls = 0;
  // F1 peaks at hit 0.8, miss 0.45, threshold 0.7 (tp = 100 there, fewer elsewhere).
  auto counts = [&](double hit, double miss, const std::vector<float>& thresholds) {
    ++calls;
    REQUIRE(thresholds.size() == eval::tuning_thresholds().size());
    std::vector<eval::ConfusionCounts> out;
    for (std::size_t t = 0; t < thresholds.size(); ++t) {
      CHECK(thresholds[t] == logodds(eval::tuning_thresholds()[t]));
      const double d = std::fabs(hit - 0.8) + std::fabs(miss - 0.45) +
                       std::fabs(eval::tuning_thresholds()[t] - 0.7);
      eval::ConfusionCounts c;
      c.tp = static_cast<std::size_t>(std::lround(100 - 50 * d));
      c.fp = 10;
      c.fn = 10;
      c.tn = 1000;
      out.push_back(c);
    }
    return out;
  };
  const std::vector<eval::OctoMapSetting> all = eval::tune_octomap(counts);
  CHECK(calls == 6 * 7);
  REQUIRE(all.size() == 6 * 7 * 5);
  CHECK(all.front().hit == 0.55);
  CHECK(all.front().miss == 0.05);
  CHECK(all[1].threshold == 0.6);
  const eval::OctoMapSetting best = eval::best_setting(all);
  CHECK(best.hit == 0.8);
  CHECK(best.miss == 0.45);
  CHECK(best.threshold == 0.7);
  CHECK(best.counts.tp == 100);
  // Ties: the first in grid order.
  std::vector<eval::OctoMapSetting> tied = all;
  for (auto& s : tied) s.counts = eval::ConfusionCounts{5, 1, 1, 1};
  CHECK(eval::best_setting(tied).hit == 0.55);
  CHECK(eval::best_setting(tied).threshold == 0.5);
  CHECK(eval::best_setting({}).hit == 0.7);  // nothing to choose from: OctoMap's defaults
}
