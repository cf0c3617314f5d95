// sim/sensitivity_grid.hpp: the grid's cells, its seeds and its neighbours.

#include <doctest/doctest.h>

#include <algorithm>
#include <set>
#include <string>

#include <knnocc/sim/sensitivity_grid.hpp>

using namespace knnocc;

TEST_CASE("sensitivity grid: 84 cells and the mixed one; tuning and report seeds disjoint") {
  const auto cells = sim::sensitivity_grid();
  REQUIRE(cells.size() == 6 * 7 * 2 + 1);
  CHECK(cells.back().mixed);
  std::set<std::string> names;
  for (const auto& c : cells) names.insert(c.name());
  CHECK(names.size() == cells.size());
  for (const std::uint64_t s : sim::kTuningSeeds)
    CHECK(std::find(sim::kReportSeeds.begin(), sim::kReportSeeds.end(), s) ==
          sim::kReportSeeds.end());
  // A cell's scene: the realistic regime with the cell's patches.
  sim::Regime realistic;
  REQUIRE(sim::find_regime("realistic", realistic));
  const sim::TreeSceneParams p = cells[20].params(101);
  CHECK(p.seed == 101);
  CHECK(p.outlier_cluster == cells[20].patch);
  CHECK(p.outlier_repeat == cells[20].lifetime);
  CHECK(p.repeat_prob == cells[20].probability);
  CHECK(p.outliers == realistic.params.outliers);
  CHECK(p.outlier_depth_gain == realistic.params.outlier_depth_gain);
  CHECK(cells.back().params(1).random_patches);
}

TEST_CASE("sensitivity grid: neighbours differ by one step along one axis") {
  const auto cells = sim::sensitivity_grid();
  std::size_t pairs = 0;
  for (std::size_t a = 0; a < cells.size(); ++a)
    for (std::size_t b = a + 1; b < cells.size(); ++b)
      pairs += sim::grid_neighbours(cells[a], cells[b]);
  // 6x7x2: (5*7 + 6*6) per probability, and 42 across the two probabilities
  CHECK(pairs == 2 * (5 * 7 + 6 * 6) + 42);
  CHECK(sim::grid_neighbours({1, 0, 1.0, false}, {2, 0, 1.0, false}));
  CHECK(sim::grid_neighbours({4, 6, 1.0, false}, {4, 8, 1.0, false}));
  CHECK(sim::grid_neighbours({4, 6, 1.0, false}, {4, 6, 0.5, false}));
  CHECK_FALSE(sim::grid_neighbours({4, 6, 1.0, false}, {6, 8, 1.0, false}));
  CHECK_FALSE(sim::grid_neighbours({8, 12, 0.75, true}, {8, 12, 1.0, false}));
}
