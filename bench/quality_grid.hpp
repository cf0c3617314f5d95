#pragma once
// bench_robust_model --grid: every model on every cell of the simulator's sensitivity grid
// (sim/sensitivity_grid.hpp), report seeds (or, with --tuning, the tuning seeds: for developing a
// model, never for reporting it), 0.1 m, 4 m crop. Per model and cell: irrelevant
// nodes and nodes in shell as % of the OctoMap model's (sums over the seeds; the paper's Table 1,
// eval/metrics.hpp) and F1 and MCC of the authors' counting against the voxelised shapes
// (eval/confusion.hpp, counts summed over the seeds). The models:
//   octomap      OctoMap's defaults (hit 0.7, miss 0.4, threshold 0.5)
//   octomap*     the oracle: the OctoMap model at the hit/miss/threshold setting with the best F1
//                on the cell's tuning seeds (the truth picks it), reported on the report seeds
//   knn          the paper's model, its defaults
//   knn2022      the authors' 2022 model (sensor/knn2022_model.hpp), its defaults, mu and sigma
//                from a first pass over the keyframes as the authors did; it gets the whole
//                clouds (it cuts at its own 4 m inner range), every other model the 4 m crop
//   knn2022o     the same with running (online) statistics
//   knn2022c     knn2022 (first pass) given the 4 m crop like the other models: no point lies
//                beyond its inner range, so its weak outer rays are gone
//   robust       RobustModel with its defaults, whatever they are at the time, or with --variant
//                NAME one of its variants (bench/robust_variants.hpp, for_each_robust_variant names
//                them), to measure a rule against the defaults on the same cells
// Then the goals, the "no cliff" figure (the largest change of a model's irrelevant share between
// neighbouring cells) and one heat-map PNG per model (bench/heat_map.hpp).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <knnocc/eval/confusion.hpp>
#include <knnocc/eval/metrics.hpp>
#include <knnocc/eval/octomap_tuning.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/sensor/knn2022_model.hpp>
#include <knnocc/sensor/knn_model.hpp>
#include <knnocc/sensor/robust_model.hpp>
#include <knnocc/sim/sensitivity_grid.hpp>
#include <knnocc/sim/tree_scene.hpp>

#include "bench_common.hpp"
#include "heat_map.hpp"
#include "knn2022_sweep.hpp"
#include "robust_variants.hpp"

namespace knnocc::bench {

struct GridOptions {
  std::size_t seeds = sim::kReportSeeds.size();  ///< report (and tuning) seeds used, from the first
  std::vector<std::size_t> patches, lifetimes;   ///< subsets (empty: all)
  std::vector<double> probabilities;
  bool mixed = true;
  bool tune = true;  ///< run the OctoMap oracle
  /// Score on the tuning seeds instead of the report seeds (for developing a model; the oracle
  /// then picks its setting on the seeds it is scored on, so it is in-sample).
  bool tuning = false;
  std::string variant;  ///< the robust column's rule variant (empty: the defaults)
  std::string png_dir = "build/grid";
};

using OctoSetting = eval::OctoMapSetting;

struct ModelScore {
  eval::Metrics table1;  ///< sums over the seeds
  eval::ConfusionCounts counts;
  void add(const eval::Metrics& m, const eval::ConfusionCounts& c) {
    table1.occupied += m.occupied;
    table1.free += m.free;
    table1.shell += m.shell;
    table1.in_shell += m.in_shell;
    table1.covered += m.covered;
    table1.irrelevant += m.irrelevant;
    table1.evaluated += m.evaluated;
    table1.free_inside += m.free_inside;
    counts += c;
  }
};

inline constexpr double kGridRes = 0.1, kGridCrop = 4.0;

template <class Model>
void score_model(const std::vector<sim::SimKeyframe>& kfs, const eval::Reference& ref,
                 const Model& model, double threshold, ModelScore& out, double crop = kGridCrop) {
  MapperOptions mo;
  mo.occupancy.occupancy_threshold = static_cast<float>(logodds(threshold));
  Mapper<Model> mapper(kGridRes, model, mo);
  sim::map_keyframes(mapper, kfs, crop);
  const auto& map = mapper.map();
  out.add(eval::evaluate(map, ref),
          eval::count_confusion(map, eval::ShapeVoxels<OcKey>(ref, map.grid())));
}

// The oracle: the setting with the best F1 of the counts summed over the tuning seeds
// (eval/octomap_tuning.hpp's grid).
inline OctoSetting tune_octomap(const sim::GridCell& cell, std::size_t seeds) {
  std::vector<sim::TreeScene> scenes;
  std::vector<std::vector<sim::SimKeyframe>> kfs;
  for (std::size_t s = 0; s < seeds; ++s) {
    scenes.emplace_back(cell.params(sim::kTuningSeeds[s]));
    kfs.push_back(scenes.back().keyframes());
  }
  return eval::best_setting(
      eval::tune_octomap([&](double hit, double miss, const std::vector<float>& thresholds) {
        std::vector<eval::ConfusionCounts> sum(thresholds.size());
        for (std::size_t s = 0; s < seeds; ++s) {
          Mapper<OctoMapModel> mapper(kGridRes, OctoMapModel::from_probabilities(hit, miss));
          sim::map_keyframes(mapper, kfs[s], kGridCrop);
          const auto counts = eval::count_confusion(
              mapper.map(), eval::ShapeVoxels<OcKey>(scenes[s].reference(), mapper.map().grid()),
              thresholds);
          for (std::size_t t = 0; t < thresholds.size(); ++t) sum[t] += counts[t];
        }
        return sum;
      }));
}

inline bool wanted(const std::vector<std::size_t>& subset, std::size_t v) {
  return subset.empty() || std::find(subset.begin(), subset.end(), v) != subset.end();
}

/// f(the robust column's model): the defaults (empty name) or the variant `name`
/// (bench/robust_variants.hpp); false, without calling f, for a name it does not hold.
template <class F>
bool with_robust_variant(const std::string& name, F&& f) {
  bool found = false;
  for_each_robust_variant([&](const std::string& n, const auto& model) {
    if (!found && n == (name.empty() ? "robust" : name)) {
      found = true;
      f(model);
    }
  });
  return found;
}

inline int run_grid(const GridOptions& opt) {
  if (!with_robust_variant(opt.variant, [](const auto&) {})) {
    std::fprintf(stderr, "bench_robust_model: unknown --variant %s (%s)\n", opt.variant.c_str(),
                 robust_variant_names().c_str());
    return 2;
  }
  std::vector<sim::GridCell> cells;
  for (const sim::GridCell& c : sim::sensitivity_grid()) {
    if (c.mixed ? !opt.mixed
                : !wanted(opt.patches, c.patch) || !wanted(opt.lifetimes, c.lifetime) ||
                      (!opt.probabilities.empty() &&
                       std::find(opt.probabilities.begin(), opt.probabilities.end(),
                                 c.probability) == opt.probabilities.end()))
      continue;
    cells.push_back(c);
  }
  const std::size_t seeds = std::clamp<std::size_t>(opt.seeds, 1, sim::kReportSeeds.size());
  const auto& scored = opt.tuning ? sim::kTuningSeeds : sim::kReportSeeds;
  const char* scored_name = opt.tuning ? "tuning" : "report";
  std::printf(
      "sensitivity grid: %zu cells, %s seeds %llu..%llu (tuning seeds %llu..%llu: the "
      "OctoMap oracle's choice%s), 0.1 m, 4 m crop\n",
      cells.size(), scored_name, (unsigned long long)scored[0],
      (unsigned long long)scored[seeds - 1], (unsigned long long)sim::kTuningSeeds[0],
      (unsigned long long)sim::kTuningSeeds[seeds - 1],
      opt.tuning ? ", in-sample: scored on the seeds that chose it" : " only");
  if (!opt.variant.empty())
    std::printf("robust column: the variant %s (bench/robust_variants.hpp)\n", opt.variant.c_str());
  const std::vector<std::string> names{"octomap",  "octomap*", "knn",   "knn2022",
                                       "knn2022o", "knn2022c", "robust"};
  const std::size_t nm = names.size();
  std::vector<std::vector<ModelScore>> score(cells.size(), std::vector<ModelScore>(nm));
  std::vector<OctoSetting> tuned(cells.size());
  const double t0 = now();
  for (std::size_t c = 0; c < cells.size(); ++c) {
    if (opt.tune) tuned[c] = tune_octomap(cells[c], seeds);
    for (std::size_t s = 0; s < seeds; ++s) {
      sim::TreeScene scene(cells[c].params(scored[s]));
      const auto kfs = scene.keyframes();
      const eval::Reference& ref = scene.reference();
      score_model(kfs, ref, OctoMapModel{}, 0.5, score[c][0]);
      if (opt.tune)
        score_model(kfs, ref, OctoMapModel::from_probabilities(tuned[c].hit, tuned[c].miss),
                    tuned[c].threshold, score[c][1]);
      score_model(kfs, ref, KnnModel{}, 0.5, score[c][2]);
      score_model(kfs, ref, Knn2022Model(knn2022_first_pass(kfs, Knn2022Params{})), 0.5,
                  score[c][3], -1.0);
      score_model(kfs, ref, Knn2022Model{}, 0.5, score[c][4], -1.0);
      score_model(kfs, ref, Knn2022Model(knn2022_first_pass(kfs, Knn2022Params{}, kGridCrop)), 0.5,
                  score[c][5]);
      with_robust_variant(
          opt.variant, [&](const auto& model) { score_model(kfs, ref, model, 0.5, score[c][6]); });
    }
    std::fprintf(stderr, "\rgrid: cell %zu of %zu (%s), %.0f s", c + 1, cells.size(),
                 cells[c].name().c_str(), now() - t0);
    std::fflush(stderr);
  }
  std::fprintf(stderr, "\n");

  auto irr_pct = [&](std::size_t c, std::size_t m) {
    const double o = double(score[c][0].table1.irrelevant);
    return o > 0 ? 100.0 * double(score[c][m].table1.irrelevant) / o : std::nan("");
  };
  auto shell_pct = [&](std::size_t c, std::size_t m) {
    const double o = double(score[c][0].table1.in_shell);
    return o > 0 ? 100.0 * double(score[c][m].table1.in_shell) / o : std::nan("");
  };
  auto used = [&](std::size_t m) { return m != 1 || opt.tune; };
  auto table = [&](const std::string& title, const char* fmt,
                   const std::function<double(std::size_t, std::size_t)>& value) {
    std::printf("\n%s\n  %-14s", title.c_str(), "cell");
    for (std::size_t m = 0; m < nm; ++m)
      if (used(m)) std::printf(" %9s", names[m].c_str());
    std::printf("\n");
    for (std::size_t c = 0; c < cells.size(); ++c) {
      std::printf("  %-14s", cells[c].name().c_str());
      for (std::size_t m = 0; m < nm; ++m)
        if (used(m)) std::printf(fmt, value(c, m));
      std::printf("\n");
    }
  };
  table(std::string("irrelevant nodes, % of the OctoMap model's (defaults; sums over the ") +
            scored_name + " seeds)",
        " %9.1f", irr_pct);
  table("nodes in reference shell, % of the OctoMap model's", " %9.1f", shell_pct);
  table(std::string("F1, authors' counting (TP/FP/FN summed over the ") + scored_name + " seeds)",
        " %9.3f", [&](std::size_t c, std::size_t m) { return score[c][m].counts.f1(); });
  table("MCC, authors' counting", " %9.3f",
        [&](std::size_t c, std::size_t m) { return score[c][m].counts.mcc(); });
  if (opt.tune) {
    std::printf(
        "\noctomap* (an oracle: the truth picks its setting per cell, on the tuning seeds): "
        "hit/miss/threshold\n");
    for (std::size_t c = 0; c < cells.size(); ++c)
      std::printf("  %-14s %.2f/%.2f/%.2f\n", cells[c].name().c_str(), tuned[c].hit, tuned[c].miss,
                  tuned[c].threshold);
  }

  // Goals and the "no cliff" figure, per model.
  std::printf("\nsummary (%s seeds; the quality goals in brackets)\n", scored_name);
  for (std::size_t m = 1; m < nm; ++m) {
    if (!used(m)) continue;
    std::size_t le10 = 0, le25 = 0, shell97 = 0, above_knn = 0, below_oracle = 0, grid_cells = 0;
    double worst = 0, worst_shell = 1e9, cliff = 0, mixed_pct = std::nan(""), f1_sum = 0;
    // above_at: the first few cells above knn, with the node counts (the rest counted)
    std::string cliff_at, above_at;
    constexpr std::size_t kNamed = 4;
    for (std::size_t c = 0; c < cells.size(); ++c) {
      const double p = irr_pct(c, m), sh = shell_pct(c, m);
      if (cells[c].mixed) {
        mixed_pct = p;
        continue;
      }
      ++grid_cells;
      f1_sum += score[c][m].counts.f1();
      le10 += p <= 10.0;
      le25 += p <= 25.0;
      shell97 += sh >= 97.0;
      if (p > irr_pct(c, 2) && ++above_knn <= kNamed)
        above_at += (above_at.empty() ? "" : ", ") + cells[c].name() + " " +
                    std::to_string(score[c][m].table1.irrelevant) + " vs " +
                    std::to_string(score[c][2].table1.irrelevant) + " nodes";
      below_oracle += opt.tune && score[c][m].counts.f1() < score[c][1].counts.f1();
      worst = std::max(worst, std::isnan(p) ? 0.0 : p);
      worst_shell = std::min(worst_shell, std::isnan(sh) ? 1e9 : sh);
      for (std::size_t d = c + 1; d < cells.size(); ++d)
        if (sim::grid_neighbours(cells[c], cells[d])) {
          const double q = irr_pct(d, m);
          if (!std::isnan(p) && !std::isnan(q) && std::fabs(p - q) > cliff) {
            cliff = std::fabs(p - q);
            cliff_at = cells[c].name() + " / " + cells[d].name();
          }
        }
    }
    if (above_knn > kNamed) above_at += ", " + std::to_string(above_knn - kNamed) + " more";
    std::printf(
        "  %-9s irrelevant <= 10 %%: %zu of %zu cells [>= 90 %%], <= 25 %%: %zu [all], worst "
        "%.1f %%; above knn in %zu [0]%s%s%s; shell >= 97 %%: %zu [all], lowest %.1f %%; mixed "
        "%.1f %% [<= 10]; largest step between neighbours %.1f points (%s) [<= 15]",
        names[m].c_str(), le10, grid_cells, le25, worst, above_knn, above_at.empty() ? "" : " (",
        above_at.c_str(), above_at.empty() ? "" : ")", shell97, worst_shell, mixed_pct, cliff,
        cliff_at.empty() ? "-" : cliff_at.c_str());
    if (opt.tune && m != 1) std::printf("; F1 below octomap* in %zu cells [0]", below_oracle);
    if (grid_cells > 0) std::printf("; mean F1 %.3f", f1_sum / double(grid_cells));
    std::printf("\n");
  }

  std::filesystem::create_directories(opt.png_dir);
  for (std::size_t m = 0; m < nm; ++m) {
    if (!used(m)) continue;
    HeatMapValues v;
    v.cells = cells;
    for (std::size_t c = 0; c < cells.size(); ++c) {
      v.irrelevant_pct.push_back(irr_pct(c, m));
      v.f1.push_back(score[c][m].counts.f1());
    }
    const std::string file = names[m] == "octomap*" ? "octomap_oracle" : names[m];
    const std::string path = opt.png_dir + "/grid_" + file + ".png";
    char title[160];
    std::snprintf(title, sizeof title, "%s%s: sensitivity grid, %s seeds %llu-%llu",
                  names[m].c_str(), m == 1 ? " (oracle-tuned OctoMap)" : "", scored_name,
                  (unsigned long long)scored[0], (unsigned long long)scored[seeds - 1]);
    write_heat_map(path, title, v);
    std::printf("wrote %s\n", path.c_str());
  }
  return 0;
}

}  // namespace knnocc::bench
