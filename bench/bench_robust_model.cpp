// bench_robust_model: the OctoMap model, the paper's k-NN model and the robust model
// (sensor/robust_model.hpp) on the simulator's outlier regimes (sim/regimes.hpp, seeds 1..N,
// Table 1 summed over the seeds) and on the real ORB-SLAM2 stereo keyframes
// (../shared/data/orbslam2_stereo_keyframes, 0.1 m, 4 m crop: the proxies of eval/multiview.hpp
// against the OctoMap model's map) and the TUM depth clouds (0.05 m: occupied voxels kept).
// --ablate also maps each regime with the robust model's parts switched off one at a time.
//
//   build/bin/bench_robust_model [--seeds N] [--ablate] [--match TEXT] [--data DIR]
//   (--match: the ablation's variants whose name contains TEXT only)
//   [--repeat N] [--cluster N]: the repeated regimes' patches re-observed by the next N keyframes
//   instead of 4, the clustered regimes' patches N features instead of 6: how the robust model's
//   rules hold on wrong matches unlike those its thresholds were measured on
//
//   build/bin/bench_robust_model --grid [--seeds N] [--patch 1,2] [--lifetime 0,4] [--prob 1]
//     [--no-mixed] [--no-tune] [--png-dir DIR]
//   the sensitivity grid on the report seeds (bench/quality_grid.hpp), heat maps in DIR
//   (default build/grid); --no-tune skips the OctoMap oracle (the slowest part)

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <knnocc/eval/metrics.hpp>
#include <knnocc/eval/multiview.hpp>
#include <knnocc/io/sequence.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/sensor/knn_model.hpp>
#include <knnocc/sensor/robust_model.hpp>
#include <knnocc/sim/regimes.hpp>
#include <knnocc/sim/tree_scene.hpp>

#include "bench_common.hpp"
#include "quality_grid.hpp"
#include "robust_variants.hpp"

using namespace knnocc;

namespace {

struct Totals {
  double in_shell = 0, irrelevant = 0, free_inside = 0, covered = 0, ms = 0;
  void add(const eval::Metrics& m) {
    in_shell += double(m.in_shell);
    irrelevant += double(m.irrelevant);
    free_inside += double(m.free_inside);
    covered += double(m.covered);
  }
};

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

template <class Model>
eval::Metrics run_sim(const std::vector<sim::SimKeyframe>& kfs, const eval::Reference& ref,
                      const Model& model, double& ms) {
  Mapper<Model> mapper(0.1, model);
  ms += median(sim::map_keyframes(mapper, kfs, 4.0)) / 1000.0;
  return eval::evaluate(mapper.map(), ref);
}

// One model over a sequence folder (as `knnocc map --crop`); the map and the median ms per
// keyframe.
template <class Model, class Use>
double run_sequence(const io::Sequence& seq, double res, double crop, const Model& model,
                    Use&& use) {
  Mapper<Model> mapper(res, model);
  std::vector<double> ms;
  std::vector<Point3d> w;
  std::vector<Point3f> wf;
  std::vector<std::uint64_t> ids;
  for (std::size_t i = 0; i < seq.size(); ++i) {
    const io::Cloud cloud = seq.load_cloud(i);
    io::keyframe_to_world(seq.pose(i), cloud, crop, w, ids);
    const double t = bench::now();
    if constexpr (Mapper<Model>::uses_map_cloud) {
      mapper.insert_keyframe(seq.pose(i).t, w, ids);
    } else {
      wf.clear();
      for (const Point3d& p : w) wf.push_back(Point3f{float(p.x), float(p.y), float(p.z)});
      mapper.insert_keyframe(seq.pose(i).t, wf);
    }
    ms.push_back(1000 * (bench::now() - t));
  }
  use(mapper.map());
  return median(ms);
}

void real_stereo(const std::string& dir, const std::vector<bench::RobustVariant>& vars) {
  const io::Sequence seq = io::Sequence::open(dir);
  eval::MapPointViews views;
  std::vector<Point3d> w;
  std::vector<std::uint64_t> ids;
  for (std::size_t i = 0; i < seq.size(); ++i) {
    io::keyframe_to_world(seq.pose(i), seq.load_cloud(i), 4.0, w, ids);
    views.add_keyframe(w, ids);
  }
  std::printf(
      "\nreal stereo keyframes (%zu, 0.1 m, 4 m crop): %zu distinct map points, seen-once %.1f %%, "
      "%zu seen by >= 3 keyframes\n",
      seq.size(), views.size(), 100 * views.seen_once_fraction(), views.count_at_least(3));
  std::printf("  %-9s %8s %8s %9s %8s %6s %8s %6s %8s\n", "model", "occupied", "isolated",
              "multiview", "ref_kept", "lost", "free_mv", "far", "ms/kf");
  OccupancyMap<OcKey> octo(0.1);
  const double octo_ms = run_sequence(seq, 0.1, 4.0, OctoMapModel{}, [&](const auto& m) {
    m.for_each_voxel([&](const OcKey& k, float v) { octo.set(k, v); });
  });
  const eval::MultiviewMetrics qo = eval::evaluate_multiview(octo, views, &octo);
  auto row = [&](const char* name, const eval::MultiviewMetrics& q, double ms) {
    std::printf(
        "  %-9s %8zu %8zu %9zu %8zu %6zu %8zu %6zu %8.3f  isolated/octomap %.0f %%, lost %.1f %% "
        "of multiview\n",
        name, q.occupied, q.isolated, q.multiview, q.reference_kept, q.lost, q.free_multiview,
        q.far, ms, qo.isolated ? 100.0 * double(q.isolated) / double(qo.isolated) : 0.0,
        q.multiview ? 100.0 * double(q.lost) / double(q.multiview) : 0.0);
  };
  row("octomap", qo, octo_ms);
  eval::MultiviewMetrics q;
  auto measure = [&](const OccupancyMap<OcKey>& m) {
    q = eval::evaluate_multiview(m, views, &octo);
  };
  const double knn_ms = run_sequence(seq, 0.1, 4.0, KnnModel{}, measure);
  row("knn", q, knn_ms);
  for (const bench::RobustVariant& v : vars) {
    const double ms = v.real(seq, measure);
    row(v.name.c_str(), q, ms);
  }
}

}  // namespace

// "1,2,4" as numbers.
template <class T>
std::vector<T> number_list(const char* text) {
  std::vector<T> out;
  for (const char* p = text; *p;) {
    char* end = nullptr;
    const double v = std::strtod(p, &end);
    if (end == p) break;
    out.push_back(static_cast<T>(v));
    p = *end == ',' ? end + 1 : end;
  }
  return out;
}

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i)
    if (!std::strcmp(argv[i], "--grid")) {
      bench::GridOptions g;
      for (int j = 1; j < argc; ++j) {
        const bool more = j + 1 < argc;
        if (!std::strcmp(argv[j], "--seeds") && more)
          g.seeds = static_cast<std::size_t>(std::max(1, std::atoi(argv[++j])));
        else if (!std::strcmp(argv[j], "--patch") && more)
          g.patches = number_list<std::size_t>(argv[++j]);
        else if (!std::strcmp(argv[j], "--lifetime") && more)
          g.lifetimes = number_list<std::size_t>(argv[++j]);
        else if (!std::strcmp(argv[j], "--prob") && more)
          g.probabilities = number_list<double>(argv[++j]);
        else if (!std::strcmp(argv[j], "--no-mixed"))
          g.mixed = false;
        else if (!std::strcmp(argv[j], "--no-tune"))
          g.tune = false;
        else if (!std::strcmp(argv[j], "--png-dir") && more)
          g.png_dir = argv[++j];
      }
      std::printf("bench_robust_model --grid (%s build)\n", KNNOCC_BENCH_BUILD_TYPE);
      return bench::run_grid(g);
    }
  int seeds = 5, first_seed = 1;
  bool ablate = false;
  std::string match;
  std::string data = "../shared/data";
  int repeat = -1, cluster = -1;  // the regimes' own unless given
  double repeat_prob = -1;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--seeds") && i + 1 < argc)
      seeds = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--ablate"))
      ablate = true;
    else if (!std::strcmp(argv[i], "--match") && i + 1 < argc)
      match = argv[++i], ablate = true;
    else if (!std::strcmp(argv[i], "--data") && i + 1 < argc)
      data = argv[++i];
    else if (!std::strcmp(argv[i], "--repeat") && i + 1 < argc)
      repeat = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--cluster") && i + 1 < argc)
      cluster = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--repeat-prob") && i + 1 < argc)
      repeat_prob = std::atof(argv[++i]);
    else if (!std::strcmp(argv[i], "--first-seed") && i + 1 < argc)
      first_seed = std::atoi(argv[++i]);
  }
  if (seeds < 1) seeds = 1;
  std::printf("bench_robust_model (%s build): tree scene seeds 1..%d, 0.1 m, 4 m crop\n",
              KNNOCC_BENCH_BUILD_TYPE, seeds);
  if (repeat >= 0 || cluster >= 0)
    std::printf(
        "regimes changed: repeated patches re-observed by %s keyframes, patches of %s "
        "features\n",
        repeat >= 0 ? std::to_string(repeat).c_str() : "their regime's",
        cluster >= 0 ? std::to_string(cluster).c_str() : "their regime's");
  std::vector<bench::RobustVariant> vars = bench::robust_variants(
      ablate,
      [](const std::vector<sim::SimKeyframe>& kfs, const eval::Reference& ref, const auto& model,
         double& ms) { return run_sim(kfs, ref, model, ms); },
      [](const io::Sequence& seq, const auto& model,
         const std::function<void(const OccupancyMap<OcKey>&)>& use) {
        return run_sequence(seq, 0.1, 4.0, model, use);
      });
  if (!match.empty())  // the default and the variants whose name contains the text
    vars.erase(std::remove_if(vars.begin() + 1, vars.end(),
                              [&](const bench::RobustVariant& v) {
                                return v.name.find(match) == std::string::npos;
                              }),
               vars.end());
  for (const sim::Regime& regime : sim::named_regimes()) {
    Totals octo, knn;
    std::vector<Totals> rob(vars.size());
    double seen_once = 0;
    for (int s = first_seed; s < first_seed + seeds; ++s) {
      sim::TreeSceneParams p = regime.params;
      p.seed = static_cast<std::uint64_t>(s);
      if (repeat >= 0 && p.outlier_repeat > 0) p.outlier_repeat = static_cast<std::size_t>(repeat);
      if (cluster >= 1 && p.outlier_cluster > 1)
        p.outlier_cluster = static_cast<std::size_t>(cluster);
      if (repeat_prob >= 0 && p.outlier_repeat > 0) p.repeat_prob = repeat_prob;
      sim::TreeScene scene(p);
      const auto kfs = scene.keyframes();
      eval::MapPointViews views;
      std::vector<Point3d> w;
      std::vector<std::uint64_t> ids;
      for (const auto& kf : kfs) {
        io::keyframe_to_world(kf.pose, kf.cloud, 4.0, w, ids);
        views.add_keyframe(w, ids);
      }
      seen_once += views.seen_once_fraction() / seeds;
      octo.add(run_sim(kfs, scene.reference(), OctoMapModel{}, octo.ms));
      knn.add(run_sim(kfs, scene.reference(), KnnModel{}, knn.ms));
      for (std::size_t v = 0; v < vars.size(); ++v)
        rob[v].add(vars[v].sim(kfs, scene.reference(), rob[v].ms));
    }
    std::printf("\nregime %-10s seen-once %.1f %% of distinct map points (sums over %d seeds)\n",
                regime.name.c_str(), 100 * seen_once, seeds);
    std::printf("  %-9s %9s %9s %10s %11s %8s %14s %14s\n", "model", "in_shell", "covered",
                "irrelevant", "free_inside", "ms/kf", "irrel/octomap", "shell/octomap");
    auto row = [&](const char* name, const Totals& t) {
      std::printf("  %-9s %9.0f %9.0f %10.0f %11.0f %8.3f %13.1f%% %13.1f%%\n", name, t.in_shell,
                  t.covered, t.irrelevant, t.free_inside, t.ms / seeds,
                  octo.irrelevant > 0 ? 100 * t.irrelevant / octo.irrelevant : 0.0,
                  octo.in_shell > 0 ? 100 * t.in_shell / octo.in_shell : 0.0);
    };
    row("octomap", octo);
    row("knn", knn);
    for (std::size_t v = 0; v < vars.size(); ++v) row(vars[v].name.c_str(), rob[v]);
  }
  const std::string stereo = data + "/orbslam2_stereo_keyframes";
  if (std::filesystem::is_directory(stereo))
    real_stereo(stereo, vars);
  else
    std::printf("\n(no %s: real stereo part skipped)\n", stereo.c_str());
  return 0;
}
