#pragma once
// bench_knn_sweep --model knn2022: the sweep behind Knn2022Model's defaults (k, p_near, p_far,
// p_miss_outer; sensor/knn2022_model.hpp). The authors' values were not found, so they are chosen
// here on the simulator's tuning seeds only (sim/sensitivity_grid.hpp: kTuningSeeds), over four
// cells of the sensitivity grid unlike each other (isolated wrong matches; patches of 4 seen over
// 4 keyframes; patches of 8 re-observed with probability 0.5; the mixed regime), by the F1 of the
// authors' counting (eval/confusion.hpp) summed over cells and seeds. The model runs as the
// authors ran it: mu and sigma from a first pass, the whole cloud (no crop: the model cuts at its
// own inner range). Reports use the report seeds (bench_robust_model --grid), never these.

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include <knnocc/eval/confusion.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/sensor/knn2022_model.hpp>
#include <knnocc/sim/sensitivity_grid.hpp>
#include <knnocc/sim/tree_scene.hpp>

#include "bench_common.hpp"

namespace knnocc::bench {

/// The first pass over simulated keyframes (as `knnocc map --model knn2022` does over a
/// sequence; crop > 0: the points within crop of their camera): the parameters with mu and
/// sigma of the whole sequence.
inline Knn2022Params knn2022_first_pass(const std::vector<sim::SimKeyframe>& kfs,
                                        const Knn2022Params& p, double crop = -1.0) {
  Knn2022FirstPass pass(p);
  std::vector<Point3d> world;
  std::vector<std::uint64_t> ids;
  for (const sim::SimKeyframe& kf : kfs) {
    io::keyframe_to_world(kf.pose, kf.cloud, crop, world, ids);
    pass.add(Point3d{kf.pose.t.x(), kf.pose.t.y(), kf.pose.t.z()}, world);
  }
  return pass.params();
}

inline int run_knn2022_sweep(std::size_t seeds) {
  const std::vector<sim::GridCell> cells{
      {1, 0, 1.0, false}, {4, 4, 1.0, false}, {8, 1, 0.5, false}, sim::sensitivity_grid().back()};
  seeds = std::clamp<std::size_t>(seeds, 1, sim::kTuningSeeds.size());
  std::printf("bench_knn_sweep --model knn2022 (%s build): tuning seeds %llu..%llu, cells",
              KNNOCC_BENCH_BUILD_TYPE, (unsigned long long)sim::kTuningSeeds[0],
              (unsigned long long)sim::kTuningSeeds[seeds - 1]);
  for (const sim::GridCell& c : cells) std::printf(" [%s]", c.name().c_str());
  std::printf(", 0.1 m, first-pass statistics, no crop\n");
  const double t0 = now();
  struct Scene {
    std::vector<sim::SimKeyframe> kfs;
    eval::Reference ref;
  };
  std::vector<Scene> scenes;
  eval::ConfusionCounts octo;
  for (const sim::GridCell& c : cells)
    for (std::size_t s = 0; s < seeds; ++s) {
      sim::TreeScene scene(c.params(sim::kTuningSeeds[s]));
      scenes.push_back({scene.keyframes(), scene.reference()});
      Mapper<OctoMapModel> m(0.1);
      sim::map_keyframes(m, scenes.back().kfs, 4.0);
      octo += eval::count_confusion(m.map(),
                                    eval::ShapeVoxels<OcKey>(scene.reference(), m.map().grid()));
    }
  struct Result {
    Knn2022Params p;
    eval::ConfusionCounts c;
  };
  std::vector<Result> results;
  for (const std::size_t k : {8u, 16u, 24u, 32u, 48u}) {
    Knn2022Params base;
    base.k = k;
    std::vector<Knn2022Params> first;  // mu, sigma per scene for this k
    for (const Scene& s : scenes) first.push_back(knn2022_first_pass(s.kfs, base));
    for (const double pn : {0.9, 0.95, 0.97, 0.99})
      for (const double pf : {0.3, 0.4, 0.45, 0.48})
        for (const double outer : {0.45, 0.49}) {
          Result r;
          r.p = base;
          r.p.p_near = pn;
          r.p.p_far = pf;
          r.p.p_miss_outer = outer;
          for (std::size_t i = 0; i < scenes.size(); ++i) {
            Knn2022Params p = r.p;
            p.fixed_statistics = true;
            p.mu = first[i].mu;
            p.sigma = first[i].sigma;
            Mapper<Knn2022Model> m(0.1, Knn2022Model(p));
            sim::map_keyframes(m, scenes[i].kfs, -1.0);
            r.c += eval::count_confusion(m.map(),
                                         eval::ShapeVoxels<OcKey>(scenes[i].ref, m.map().grid()));
          }
          results.push_back(r);
        }
  }
  std::sort(results.begin(), results.end(),
            [](const Result& a, const Result& b) { return a.c.f1() > b.c.f1(); });
  std::printf("OctoMap model (defaults, 4 m crop), same scenes: F1 %.4f MCC %.4f\n", octo.f1(),
              octo.mcc());
  std::printf("%zu combinations, best F1 first (counts summed over cells and seeds):\n",
              results.size());
  std::printf("%4s %7s %6s %7s %8s %8s\n", "k", "p_near", "p_far", "outer", "F1", "MCC");
  for (std::size_t i = 0; i < results.size(); ++i) {
    if (i == 12 && results.size() > 15) {
      std::printf("  ...\n");
      i = results.size() - 3;
    }
    const Result& r = results[i];
    std::printf("%4zu %7g %6g %7g %8.4f %8.4f\n", r.p.k, r.p.p_near, r.p.p_far, r.p.p_miss_outer,
                r.c.f1(), r.c.mcc());
  }
  std::printf("\n%.1f s\n", now() - t0);
  return 0;
}

}  // namespace knnocc::bench
