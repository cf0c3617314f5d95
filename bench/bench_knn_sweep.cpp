// bench_knn_sweep: the documented sweep behind the k-NN model's default parameters.
// For every combination of k, w, P_u, P_w and s_limit, the simulated tree scene (the paper's
// experiment, `knnocc demo`) is mapped over several seeds with the k-NN model and compared with
// the OctoMap model on the same keyframes. Prints the best --top combinations (default 25) that
// keep >= 97 % of the OctoMap model's nodes in the reference shell (fewest irrelevant nodes
// first), how many meet both goals, and the least favourable ones.
//
//   build/bin/bench_knn_sweep [--seeds N] [--top N]
//   build/bin/bench_knn_sweep --model knn2022 [--seeds N]   the 2022 model's sweep
//   (bench/knn2022_sweep.hpp)

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include <knnocc/eval/metrics.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/sensor/knn_model.hpp>
#include <knnocc/sim/tree_scene.hpp>

#include "bench_common.hpp"
#include "knn2022_sweep.hpp"

using namespace knnocc;

namespace {

struct Totals {
  double in_shell = 0, irrelevant = 0, free_inside = 0, covered = 0;
  void add(const eval::Metrics& m) {
    in_shell += double(m.in_shell);
    irrelevant += double(m.irrelevant);
    free_inside += double(m.free_inside);
    covered += double(m.covered);
  }
};

struct Scene {
  std::vector<sim::SimKeyframe> keyframes;
  eval::Reference reference;
};

template <class Model>
eval::Metrics run(const Scene& s, const Model& model) {
  Mapper<Model> mapper(0.1, model);
  sim::map_keyframes(mapper, s.keyframes, 4.0);
  return eval::evaluate(mapper.map(), s.reference);
}

const char* const kUsage =
    "usage: build/bin/bench_knn_sweep [--seeds N] [--top N] [--model knn|knn2022]\n"
    "  the k-NN model's sweep (the best --top combinations, default 25), or the 2022 model's\n";

}  // namespace

int main(int argc, char** argv) {
  int seeds = 5, top = 25;
  bool knn2022 = false;
  for (int i = 1; i < argc; ++i) {
    const bool more = i + 1 < argc;
    if (!std::strcmp(argv[i], "--help") || !std::strcmp(argv[i], "-h")) {
      std::printf("%s", kUsage);
      return 0;
    }
    if (!std::strcmp(argv[i], "--seeds") && more) {
      seeds = std::atoi(argv[++i]);
    } else if (!std::strcmp(argv[i], "--top") && more) {
      top = std::atoi(argv[++i]);
    } else if (!std::strcmp(argv[i], "--model") && more &&
               (!std::strcmp(argv[i + 1], "knn") || !std::strcmp(argv[i + 1], "knn2022"))) {
      knn2022 = !std::strcmp(argv[++i], "knn2022");
    } else {
      std::fprintf(stderr, "bench_knn_sweep: unknown or incomplete option %s\n%s", argv[i], kUsage);
      return 2;
    }
  }
  if (seeds < 1) seeds = 1;
  if (knn2022) return bench::run_knn2022_sweep(static_cast<std::size_t>(seeds));
  std::printf("bench_knn_sweep (%s build): simulated tree scene, seeds 1..%d, 0.1 m, 4 m crop\n",
              KNNOCC_BENCH_BUILD_TYPE, seeds);
  const double t0 = bench::now();
  std::vector<Scene> scenes;
  Totals octo;
  for (int s = 1; s <= seeds; ++s) {
    sim::TreeSceneParams p;
    p.seed = static_cast<std::uint64_t>(s);
    sim::TreeScene scene(p);
    scenes.push_back({scene.keyframes(), scene.reference()});
    octo.add(run(scenes.back(), OctoMapModel{}));
  }
  std::printf(
      "OctoMap model, sums over the seeds: in_shell %.0f irrelevant %.0f free_inside %.0f\n\n",
      octo.in_shell, octo.irrelevant, octo.free_inside);

  struct Result {
    KnnModelParams p;
    Totals t;
  };
  std::vector<Result> results;
  const double inf = std::numeric_limits<double>::infinity();
  std::size_t combos = 0;
  for (const std::size_t k : {4u, 6u, 8u, 10u, 15u})
    for (const double s_limit : {inf, 0.5})
      for (const double w : {-0.5, 0.0, 0.5, 1.0})
        for (const double pu : {0.7, 0.8, 0.9})
          for (const double pw : {0.55, 0.6, 0.65}) {
            if (!(pu > pw)) continue;
            KnnModelParams p;
            p.k = k;
            p.s_limit = s_limit;
            p.w = w;
            p.p_upper = pu;
            p.p_w = pw;
            Result r{p, {}};
            for (const Scene& s : scenes) r.t.add(run(s, KnnModel(p)));
            results.push_back(r);
            ++combos;
          }
  std::sort(results.begin(), results.end(), [](const Result& a, const Result& b) {
    if (a.t.irrelevant != b.t.irrelevant) return a.t.irrelevant < b.t.irrelevant;
    return a.t.in_shell > b.t.in_shell;
  });
  std::printf(
      "%zu combinations; those with nodes in shell >= 97 %% of the OctoMap model's, fewest "
      "irrelevant first (percentages of the OctoMap model's sums):\n",
      combos);
  std::printf("%4s %8s %6s %6s %6s %12s %12s %12s\n", "k", "s_limit", "w", "P_u", "P_w",
              "irrelevant%", "in_shell%", "free_inside%");
  int shown = 0;
  for (const Result& r : results) {
    if (r.t.in_shell < 0.97 * octo.in_shell) continue;
    if (shown++ == top) break;
    std::printf("%4zu %8g %6g %6g %6g %12.1f %12.1f %12.1f\n", r.p.k, r.p.s_limit, r.p.w,
                r.p.p_upper, r.p.p_w, 100 * r.t.irrelevant / octo.irrelevant,
                100 * r.t.in_shell / octo.in_shell, 100 * r.t.free_inside / octo.free_inside);
  }
  std::size_t both = 0;
  for (const Result& r : results)
    both += r.t.in_shell >= 0.97 * octo.in_shell && r.t.irrelevant <= 0.10 * octo.irrelevant;
  std::printf(
      "\n%zu of %zu combinations meet both goals (irrelevant <= 10 %%, in shell >= 97 %%)\n", both,
      combos);
  std::printf("the least favourable ones (most irrelevant nodes):\n");
  for (std::size_t i = results.size() > 5 ? results.size() - 5 : 0; i < results.size(); ++i) {
    const Result& r = results[i];
    std::printf("%4zu %8g %6g %6g %6g %12.1f %12.1f %12.1f\n", r.p.k, r.p.s_limit, r.p.w,
                r.p.p_upper, r.p.p_w, 100 * r.t.irrelevant / octo.irrelevant,
                100 * r.t.in_shell / octo.in_shell, 100 * r.t.free_inside / octo.free_inside);
  }
  std::printf("\n%.1f s\n", bench::now() - t0);
  return 0;
}
