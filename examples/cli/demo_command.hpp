#pragma once
// knnocc demo: the embedded default job, the paper's experiment (section 4) on the simulated tree
// scene: both inverse sensor models map the same keyframes, and the maps are compared with the
// reference shapes (Table 1), over several seeds. Needs no data files.
// `knnocc demo --scene room` runs the LiDAR room demo instead (room_demo.hpp).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <knnocc/eval/metrics.hpp>
#include <knnocc/eval/reference.hpp>
#include <knnocc/io/octomap_tree.hpp>
#include <knnocc/io/voxel_export.hpp>
#include <knnocc/io/voxel_list.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/sensor/knn_model.hpp>
#include <knnocc/sim/tree_scene.hpp>

#include "args.hpp"
#include "map_command.hpp"
#include "map_picture.hpp"
#include "room_demo.hpp"

namespace knnocc::cli {

inline const char* demo_help() {
  return R"(usage: knnocc demo [--seeds N] [--first-seed S] [--res R] [--crop M] [--out DIR]
                   [k-NN model flags of `knnocc map`: --k --w --p-upper --p-w --p-free --s-limit]
       knnocc demo --scene room      (the LiDAR room demo, see knnocc demo --scene room --help)

The paper's experiment (section 4) on the simulated tree scene (`knnocc sim`): for each seed the
same keyframes (points within --crop 4 m of the camera) are mapped at --res 0.1 m with the OctoMap
model and with the k-NN model, and each map is compared with the reference shapes (`knnocc eval`).
Prints one row per seed and model, then Table 1 as mean and standard deviation over the seeds,
and the k-NN model's figures relative to the OctoMap model's.
  --seeds N        how many seeds (default 5), starting at --first-seed (default 1)
  --out DIR        also write, for the first seed: the sequence folder (DIR/scene), the reference
                   (DIR/scene/reference.txt) and both maps (<model> = octomap, knn) as OctoMap
                   binary trees for octovis (DIR/<model>.bt), voxel lists (DIR/<model>.voxels),
                   occupied voxels as PLY cubes coloured by height (DIR/<model>_occupied.ply)
                   and top/side pictures (DIR/<model>.png); DIR must be new or an empty
                   folder (built aside as DIR.tmp-XXXXXX and renamed when complete)
)";
}

namespace demo {

struct Row {
  eval::Metrics m;
  double median_ms = 0;
};

template <class Model>
Row run_model(const std::vector<sim::SimKeyframe>& kfs, const eval::Reference& ref, double res,
              double crop, const Model& model, const std::string& out_dir, const char* name) {
  Mapper<Model> mapper(res, model);
  std::vector<double> us = sim::map_keyframes(mapper, kfs, crop);
  std::sort(us.begin(), us.end());
  Row row{eval::evaluate(mapper.map(), ref), us.empty() ? 0.0 : us[us.size() / 2] / 1000.0};
  if (!out_dir.empty()) {
    const auto& map = mapper.map();
    const std::string base = (std::filesystem::path(out_dir) / name).string();
    io::write_voxel_list(base + ".voxels", io::voxel_records(map));
    io::write_bt(base + ".bt", map);
    io::VoxelExportOptions cubes;
    cubes.shape = io::VoxelShape::cubes;
    io::write_voxels_ply(base + "_occupied.ply", map, cubes);
    write_map_png(base + ".png", map);
  }
  return row;
}

struct Spread {
  double mean = 0, sd = 0;
};
template <class F>
Spread spread(const std::vector<Row>& rows, F f) {
  Spread s;
  for (const Row& r : rows) s.mean += f(r);
  s.mean /= static_cast<double>(rows.size());
  for (const Row& r : rows) s.sd += (f(r) - s.mean) * (f(r) - s.mean);
  s.sd = rows.size() > 1 ? std::sqrt(s.sd / static_cast<double>(rows.size() - 1)) : 0.0;
  return s;
}

}  // namespace demo

inline int run_demo(const std::vector<std::string>& argv) {
  const auto at = std::find(argv.begin(), argv.end(), "--scene");
  if (at != argv.end() && at + 1 != argv.end()) {
    if (at[1] == "room") return run_room_demo(argv);
    if (at[1] != "tree") throw UsageError("--scene must be tree or room, got '" + at[1] + "'");
  }
  const Args args(argv,
                  {"--scene", "--seeds", "--first-seed", "--res", "--crop", "--out", "--k", "--w",
                   "--p-upper", "--p-w", "--p-free", "--s-limit"},
                  {});
  if (args.help()) {
    std::fputs(demo_help(), stdout);
    return 0;
  }
  const long seeds = args.integer("--seeds", 5), first = args.integer("--first-seed", 1);
  if (seeds < 1 || seeds > 1000) throw UsageError("--seeds must be in [1, 1000]");
  if (first < 0 || first > 1000000000) throw UsageError("--first-seed must be in [0, 1e9]");
  const double res = args.number("--res", 0.1);
  if (!(res >= 0.02 && res <= 1.0)) throw UsageError("--res must be in [0.02, 1] for the demo");
  const double crop = args.number("--crop", 4.0);
  if (!(crop > 0)) throw UsageError("--crop must be > 0");
  const KnnModel knn(knn_params(args));
  const KnnModelParams& kp = knn.params();
  const std::string out = args.str("--out");
  if (args.has("--out") && out.empty()) throw UsageError("--out needs a folder name, got ''");
  // Refuses a non-empty folder before any work; the folder is built aside, renamed at the end.
  std::unique_ptr<io::StagingDir> stage;
  if (!out.empty()) stage = std::make_unique<io::StagingDir>(out);

  std::printf(
      "knnocc demo: the paper's experiment on the simulated tree scene (stereo camera circling at "
      "3.5 m),\n%ld seeds, %g m map, points within %g m; k-NN model k %zu w %g P_u %g P_w %g "
      "s_limit %g\n\n",
      seeds, res, crop, kp.k, kp.w, kp.p_upper, kp.p_w, kp.s_limit);
  std::printf("%-5s %-8s %8s %8s %6s %8s %8s %10s %11s %8s\n", "seed", "model", "occupied", "free",
              "shell", "in_shell", "covered", "irrelevant", "free_inside", "ms/kf");
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<demo::Row> octo_rows, knn_rows;
  std::size_t shell = 0, points = 0, outliers = 0;
  for (long s = first; s < first + seeds; ++s) {
    sim::TreeSceneParams sp;
    sp.seed = static_cast<std::uint64_t>(s);
    sim::TreeScene scene(sp);
    const auto kfs = scene.keyframes();
    for (const auto& kf : kfs) {
      points += kf.cloud.points.size();
      outliers += kf.outliers;
    }
    std::string dir;
    if (!out.empty() && s == first) {
      dir = stage->path();
      const std::string seq = (std::filesystem::path(dir) / "scene").string();
      std::vector<io::Pose> poses;
      std::vector<const io::Cloud*> clouds;
      for (const auto& kf : kfs) {
        poses.push_back(kf.pose);
        clouds.push_back(&kf.cloud);
      }
      io::write_sequence(seq, poses, clouds);
      eval::write_reference((std::filesystem::path(seq) / "reference.txt").string(),
                            scene.reference());
    }
    const demo::Row o =
        demo::run_model(kfs, scene.reference(), res, crop, OctoMapModel{}, dir, "octomap");
    const demo::Row k = demo::run_model(kfs, scene.reference(), res, crop, knn, dir, "knn");
    for (const auto& [name, r] : {std::pair<const char*, const demo::Row&>{"octomap", o},
                                  std::pair<const char*, const demo::Row&>{"knn", k}})
      std::printf("%-5ld %-8s %8zu %8zu %6zu %8zu %8zu %10zu %11zu %8.3f\n", s, name, r.m.occupied,
                  r.m.free, r.m.shell, r.m.in_shell, r.m.covered, r.m.irrelevant, r.m.free_inside,
                  r.median_ms);
    octo_rows.push_back(o);
    knn_rows.push_back(k);
    shell += o.m.shell;
  }

  using demo::spread;
  auto table_row = [&](const char* name, const std::vector<demo::Row>& rows) {
    const auto a = spread(rows, [](const demo::Row& r) { return double(r.m.in_shell); });
    const auto b = spread(rows, [](const demo::Row& r) { return double(r.m.covered); });
    const auto c = spread(rows, [](const demo::Row& r) { return double(r.m.irrelevant); });
    const auto d = spread(rows, [](const demo::Row& r) { return double(r.m.free_inside); });
    std::printf("%-14s %9.1f ± %-5.1f %9.1f ± %-5.1f %9.1f ± %-5.1f %9.1f ± %-5.1f\n", name, a.mean,
                a.sd, b.mean, b.sd, c.mean, c.sd, d.mean, d.sd);
  };
  std::printf(
      "\nTable 1 (mean ± sd over %ld seeds; the reference shell has %.0f voxels on average)\n"
      "%-14s %17s %17s %17s %17s\n",
      seeds, double(shell) / double(seeds), "model", "nodes in shell", "nodes covered",
      "irrelevant nodes", "free inside objs");
  table_row("OctoMap model", octo_rows);
  table_row("k-NN model", knn_rows);

  auto total = [](const std::vector<demo::Row>& rows, auto f) {
    double t = 0;
    for (const auto& r : rows) t += f(r);
    return t;
  };
  const double irr_o = total(octo_rows, [](const demo::Row& r) { return double(r.m.irrelevant); });
  const double irr_k = total(knn_rows, [](const demo::Row& r) { return double(r.m.irrelevant); });
  const double sh_o = total(octo_rows, [](const demo::Row& r) { return double(r.m.in_shell); });
  const double sh_k = total(knn_rows, [](const demo::Row& r) { return double(r.m.in_shell); });
  // Ratios of sums; without OctoMap-model nodes to compare with, a goal cannot be judged.
  const double irr_pct = irr_o > 0 ? 100.0 * irr_k / irr_o : 0.0;
  const double shell_pct = sh_o > 0 ? 100.0 * sh_k / sh_o : 0.0;
  const char* none = "n/a: the OctoMap model has none";
  const char* irr_goal = irr_o == 0 ? none : irr_pct <= 10.0 ? "met" : "NOT met";
  const char* shell_goal = sh_o == 0 ? none : shell_pct >= 97.0 ? "met" : "NOT met";
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf(
      "\nk-NN model / OctoMap model over all seeds: irrelevant nodes %.1f %% (goal <= 10 %%: %s), "
      "nodes in shell %.1f %% (goal >= 97 %%: %s)\n"
      "(paper, real data: irrelevant 4 / 33 = 12.1 %%, nodes in shell 387 / 399 = 97.0 %%)\n"
      "%zu keyframe points, %zu of them wrong stereo matches; %.2f s in all\n",
      irr_pct, irr_goal, shell_pct, shell_goal, points, outliers, seconds);
  if (stage) stage->commit();
  if (!out.empty())
    std::printf("wrote %s/{octomap,knn}{.bt,.voxels,_occupied.ply,.png} and %s/scene/\n",
                out.c_str(), out.c_str());
  return 0;
}

}  // namespace knnocc::cli
