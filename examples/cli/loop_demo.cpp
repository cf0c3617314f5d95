// knnocc demo --scene loop: mapping under SLAM corrections. The simulated tree scene is seen by a
// camera whose tracking drifts (sim/drift.hpp); local bundle adjustment re-poses recent keyframes
// every 10 keyframes and the loop closure after the last keyframe re-poses them all. For both
// sensor models three maps are built: from the drifted estimates without correction (doubled
// surfaces), live-corrected (LiveMapper, each snapshot applied as it arrives), and from the true
// poses. The demo checks that the last two are identical (every voxel's log-odds bit for bit, and
// the k-NN tracker's N, mu, sigma) and prints Table 1 for all three and each correction's time.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <knnocc/eval/metrics.hpp>
#include <knnocc/io/octomap_tree.hpp>
#include <knnocc/live/live_mapper.hpp>
#include <knnocc/map/same_voxels.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/sensor/knn_model.hpp>
#include <knnocc/sim/drift.hpp>
#include <knnocc/sim/tree_scene.hpp>

#include "args.hpp"
#include "commands.hpp"
#include "live_corrections.hpp"
#include "map_picture.hpp"

namespace knnocc::cli {

namespace {

CommandSpec make_loop_demo_spec() {
  CommandSpec s;
  s.name = "demo --scene loop";
  s.summary = "mapping under SLAM corrections: drifted, live-corrected and true-pose maps";
  s.usage = "knnocc demo --scene loop [--seed S] [--drift DEG] [--res R] [--crop M] [--out DIR]";
  s.text =
      R"(Mapping under SLAM corrections on the simulated tree scene (`knnocc sim --drift`): the camera's
heading estimate drifts DEG degrees per keyframe plus jitter; local bundle adjustment re-poses the
last 5 keyframes every 10 keyframes, and the loop closure after the last keyframe re-poses all of
them to their true poses. For the OctoMap and the k-NN model it builds
  drifted    from the drifted estimates, never corrected (doubled surfaces)
  live       LiveMapper, each correction applied when it arrives
  true       from the true poses
checks that live and true are identical (exit status 1 if not), and prints Table 1 for the three
and the time each correction took.
)";
  s.groups.push_back(
      {"options",
       {Option::text("--scene", "NAME", "loop for this demo").one_of({"tree", "room", "loop"}),
        Option::integer("--seed", "S", "random seed of the scene and the drift")
            .fallback("1")
            .at_least(0),
        Option::number("--drift", "DEG", "heading drift per keyframe in degrees")
            .fallback("0.1")
            .at_least(0)
            .at_most(10),
        Option::number("--res", "R", "voxel edge in metres")
            .fallback("0.1")
            .at_least(0.02)
            .at_most(1),
        Option::number("--crop", "M", "keep the points within M of their camera")
            .fallback("4")
            .above(0),
        Option::text("--out", "DIR", "also write <model>_<map>.png and .bt per map into DIR")},
       ""});
  return s;
}

}  // namespace

const CommandSpec& loop_demo_spec() {
  static const CommandSpec spec = make_loop_demo_spec();
  return spec;
}

namespace loop_demo {

struct Correction {
  std::size_t after = 0, changed = 0, replayed = 0;
  bool rebuilt = false;
  double ms = 0;
};

template <class Model>
bool run_model(const char* name, const Model& model, const std::vector<sim::SimKeyframe>& kfs,
               const sim::DriftedRun& run, const eval::Reference& ref, double res, double crop,
               const std::string& out) {
  auto with_poses = [&](const std::vector<io::Pose>& poses) {
    std::vector<sim::SimKeyframe> moved = kfs;
    for (std::size_t i = 0; i < moved.size(); ++i) moved[i].pose = poses[i];
    return moved;
  };
  std::vector<io::Pose> truth;
  for (const auto& kf : kfs) truth.push_back(kf.pose);
  Mapper<Model> drifted(res, model), exact(res, model);
  sim::map_keyframes(drifted, with_poses(run.tracked), crop);
  sim::map_keyframes(exact, with_poses(truth), crop);

  LiveMapper<Model, OcKey, EigenPose> live(res, model);
  std::vector<Correction> corrections;
  for (std::size_t i = 0; i < kfs.size(); ++i) {
    std::vector<Point3f> pts;
    std::vector<std::uint64_t> ids;
    const io::Cloud& c = kfs[i].cloud;
    for (std::size_t j = 0; j < c.points.size(); ++j) {
      const Point3f& p = c.points[j];
      if (!(std::sqrt(double(p.x) * p.x + double(p.y) * p.y + double(p.z) * p.z) <= crop)) continue;
      pts.push_back(p);
      ids.push_back(c.ids[j]);
    }
    if constexpr (!LiveMapper<Model>::uses_map_cloud) ids.clear();
    live.add(i, EigenPose::from(run.tracked[i]), std::move(pts), std::move(ids));
    const auto snap = run.snapshots.find(i);
    if (snap == run.snapshots.end()) continue;
    std::vector<std::pair<std::uint64_t, EigenPose>> poses;
    for (std::size_t j = 0; j < snap->second.size(); ++j)
      poses.emplace_back(j, EigenPose::from(snap->second[j]));
    const auto a = std::chrono::steady_clock::now();
    live.repose(poses);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - a).count();
    const LiveUpdate& u = live.last_update();
    corrections.push_back({i, u.changed, u.replayed, u.rebuilt, ms});
  }

  bool same = same_voxels(live.map(), exact.map());
  if constexpr (LiveMapper<Model>::uses_map_cloud) {
    const auto &a = live.tracker(), &b = exact.tracker();
    same = same && a.size() == b.size() && a.N() == b.N() && a.mu() == b.mu() &&
           a.sigma() == b.sigma();
  }
  std::printf("\n%s model\n%-8s %8s %8s %8s %8s %10s %11s\n", name, "map", "occupied", "free",
              "in_shell", "covered", "irrelevant", "free_inside");
  for (const auto& [label, map] :
       {std::pair<const char*, const OccupancyMap<OcKey>*>{"drifted", &drifted.map()},
        {"live", &live.map()},
        {"true", &exact.map()}}) {
    const eval::Metrics m = eval::evaluate(*map, ref);
    std::printf("%-8s %8zu %8zu %8zu %8zu %10zu %11zu\n", label, m.occupied, m.free, m.in_shell,
                m.covered, m.irrelevant, m.free_inside);
    if (!out.empty()) {
      const std::string base =
          (std::filesystem::path(out) / (std::string(name) + "_" + label)).string();
      write_map_png(base + ".png", *map, UpAxis{},
                    std::string(name) + " model, " + label + " poses");
      io::write_bt(base + ".bt", *map);
    }
  }
  std::printf("corrections (after keyframe: re-posed, replayed keyframes, ms):");
  for (const Correction& c : corrections)
    std::printf(" %zu: %zu, %zu%s, %.2f;", c.after, c.changed, c.replayed,
                c.rebuilt ? " (rebuilt)" : "", c.ms);
  std::printf("\nlive == true: %s (%zu voxels%s)\n", same ? "identical" : "DIFFERENT",
              live.map().num_voxels(),
              LiveMapper<Model>::uses_map_cloud ? ", tracker N mu sigma" : "");
  return same;
}

}  // namespace loop_demo

int run_loop_demo(const Args& args) {
  const long seed = args.integer("--seed");
  const double drift = args.number("--drift");
  const double res = args.number("--res");
  const double crop = args.number("--crop");
  const std::string out = args.str("--out");
  if (!out.empty()) std::filesystem::create_directories(out);

  sim::TreeSceneParams sp;
  sp.seed = static_cast<std::uint64_t>(seed);
  sim::TreeScene scene(sp);
  const auto kfs = scene.keyframes();
  std::vector<io::Pose> truth;
  for (const auto& kf : kfs) truth.push_back(kf.pose);
  sim::DriftParams dp;
  dp.heading_drift = drift * M_PI / 180.0;
  dp.seed = sp.seed;
  const sim::DriftedRun run = sim::drift_run(truth, dp);
  std::printf(
      "knnocc demo --scene loop: %zu keyframes circling the tree, heading drift %g deg per "
      "keyframe (up to %.2f m off uncorrected), %zu corrections; %g m map, points within %g m\n",
      kfs.size(), drift, run.max_offset, run.snapshots.size(), res, crop);
  bool ok =
      loop_demo::run_model("OctoMap", OctoMapModel{}, kfs, run, scene.reference(), res, crop, out);
  ok = loop_demo::run_model("k-NN", KnnModel{}, kfs, run, scene.reference(), res, crop, out) && ok;
  std::printf("\n%s\n", ok ? "check: live-corrected maps equal the maps from the true poses"
                           : "check FAILED: a live-corrected map differs from the true-pose map");
  return ok ? 0 : 1;
}

}  // namespace knnocc::cli
