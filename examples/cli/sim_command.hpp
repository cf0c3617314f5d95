#pragma once
// knnocc sim: writes the simulated tree scene of the paper's experiment as a sequence folder.

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <knnocc/eval/reference.hpp>
#include <knnocc/io/sequence.hpp>
#include <knnocc/sim/tree_scene.hpp>

#include "args.hpp"
#include "output_set.hpp"

namespace knnocc::cli {

inline const char* sim_help() {
  return R"(usage: knnocc sim --out DIR [--seed S] [--keyframes N] [--outliers F]

Simulates the paper's experiment (section 4.1): a stereo camera (f 700 px, baseline 0.12 m,
disparity noise 0.5 px) circles a potted tree at 3.5 m; foliage = ellipsoid, pot = cuboid, ground
plane z = 0. Sparse feature points with persistent map-point ids (stereo depth noise growing with
range), a fraction of wrong stereo matches. Writes
  DIR/poses.txt, DIR/clouds/NNNNNN.ply   a sequence folder (camera frame, `id` property), for
                                         `knnocc map --input DIR --crop 4 --res 0.1 ...`
  DIR/reference.txt                      the true shapes, for `knnocc eval`
and prints: keyframes N points N outliers N map_points N
options:
  --seed S          random seed (default 1); the same scene for a seed with this build
  --keyframes N     keyframes around the circle (default 60)
  --outliers F      fraction of wrong stereo matches per keyframe (default 0.08, in [0, 1))
DIR must be new or an empty folder: it is written aside (DIR.tmp-XXXXXX) and renamed when
complete, so a failed run leaves no partial folder.
)";
}

inline sim::TreeSceneParams sim_params(const Args& args) {
  sim::TreeSceneParams p;
  const long seed = args.integer("--seed", 1);
  if (seed < 0) throw UsageError("--seed must be >= 0");
  p.seed = static_cast<std::uint64_t>(seed);
  const long n = args.integer("--keyframes", static_cast<long>(p.keyframes));
  if (n < 1 || n > 100000) throw UsageError("--keyframes must be in [1, 100000]");
  p.keyframes = static_cast<std::size_t>(n);
  p.outliers = args.number("--outliers", p.outliers);
  if (!(p.outliers >= 0 && p.outliers < 1)) throw UsageError("--outliers must be in [0, 1)");
  return p;
}

inline int run_sim(const std::vector<std::string>& argv) {
  const Args args(argv, {"--out", "--seed", "--keyframes", "--outliers"}, {});
  if (args.help()) {
    std::fputs(sim_help(), stdout);
    return 0;
  }
  const std::string out = args.required("--out");
  io::StagingDir stage(out);  // refuses a non-empty folder before any work; renamed at the end
  sim::TreeScene scene(sim_params(args));
  const auto keyframes = scene.keyframes();
  std::vector<io::Pose> poses;
  std::vector<const io::Cloud*> clouds;
  std::size_t points = 0, outliers = 0;
  std::vector<std::uint64_t> ids;
  for (const auto& kf : keyframes) {
    poses.push_back(kf.pose);
    clouds.push_back(&kf.cloud);
    points += kf.cloud.points.size();
    outliers += kf.outliers;
    ids.insert(ids.end(), kf.cloud.ids.begin(), kf.cloud.ids.end());
  }
  std::sort(ids.begin(), ids.end());
  const auto distinct = static_cast<std::size_t>(std::unique(ids.begin(), ids.end()) - ids.begin());
  io::write_sequence(stage.path(), poses, clouds);
  eval::write_reference((std::filesystem::path(stage.path()) / "reference.txt").string(),
                        scene.reference());
  stage.commit();
  std::printf("keyframes %zu points %zu outliers %zu map_points %zu\n", keyframes.size(), points,
              outliers, distinct);
  return 0;
}

}  // namespace knnocc::cli
