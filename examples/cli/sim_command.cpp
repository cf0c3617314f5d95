// knnocc sim: writes the simulated tree scene of the paper's experiment as a sequence folder.

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <knnocc/eval/reference.hpp>
#include <knnocc/io/sequence.hpp>
#include <knnocc/sim/drift.hpp>
#include <knnocc/sim/regimes.hpp>
#include <knnocc/sim/tree_scene.hpp>

#include "args.hpp"
#include "commands.hpp"
#include "output_set.hpp"
#include "resource_limits.hpp"

namespace knnocc::cli {

namespace {

CommandSpec make_sim_spec() {
  const sim::TreeSceneParams p;
  CommandSpec s;
  s.name = "sim";
  s.summary = "write the simulated tree scene as a sequence folder plus its reference shapes";
  s.usage =
      "knnocc sim --out DIR [--seed S] [--keyframes N] [--outliers F] [--drift DEG]\n"
      "                  [--regime NAME] [--cluster N] [--repeat N] [--repeat-prob P] "
      "[--depth-gain G]";
  s.text =
      R"(Simulates the paper's experiment (section 4.1): a stereo camera (f 700 px, baseline 0.12 m,
disparity noise 0.5 px) circles a potted tree at 3.5 m; foliage = ellipsoid, pot = cuboid, ground
plane z = 0. Sparse feature points with persistent map-point ids (stereo depth noise growing with
range), a fraction of wrong stereo matches. Writes
  DIR/poses.txt, DIR/clouds/NNNNNN.ply   a sequence folder (camera frame, `id` property), for
                                         `knnocc map --input DIR --crop 4 --res 0.1 ...`
  DIR/reference.txt                      the true shapes, for `knnocc eval`
and prints: keyframes N points N outliers N map_points N seen_once F
(seen_once: fraction of the distinct map points within 4 m that one keyframe alone observes;
../shared/data/orbslam2_stereo_keyframes: 0.066, see `knnocc eval --ids`)
DIR must be new or an empty folder: it is written aside (DIR.tmp-XXXXXX) and renamed when
complete, so a failed run leaves no partial folder. A run whose output would exceed 1 GB is
refused before any work (with --drift the snapshots grow with the square of --keyframes: 10,000
keyframes write about 0.9 GB).
)";
  s.groups.push_back(
      {"options",
       {Option::text("--out", "DIR", "the sequence folder to write").alias("-o").required(),
        Option::integer("--seed", "S", "random seed; the same scene for a seed with this build")
            .fallback("1")
            .at_least(0),
        Option::integer("--keyframes", "N", "keyframes around the circle")
            .fallback(std::to_string(p.keyframes))
            .at_least(1)
            .at_most(100000),
        Option::number("--outliers", "F", "fraction of wrong stereo matches per keyframe")
            .fallback_text("0.08, or the --regime's")
            .at_least(0)
            .below(1),
        Option::number("--drift", "DEG",
                       "odometry drift: DIR/poses.txt holds tracking estimates whose heading "
                       "drifts DEG degrees per keyframe (plus jitter); DIR/corrections/"
                       "after_NNNNNN.txt the SLAM corrections (local bundle adjustment every 10 "
                       "keyframes, the loop closure after the last: true poses), for `knnocc map "
                       "--corrections`; DIR/truth/ the same keyframes at their true poses. Prints "
                       "one more line: drift DEG corrections N max_offset_m X")
            .fallback_text("no drift")
            .at_least(0)
            .at_most(10),
        Option::text("--regime", "NAME",
                     "start from a named outlier regime (see `knnocc demo --help`); the flags "
                     "below override it")
            .fallback("isolated")
            .one_of({"isolated", "clustered", "repeated", "realistic"})},
       ""});
  s.groups.push_back(
      {"wrong matches (override --regime)",
       {Option::integer("--cluster", "N",
                        "each wrong match a patch of N features within 3 cm sharing its depth "
                        "error")
            .fallback_text("the --regime's")
            .at_least(1)
            .at_most(100),
        Option::integer("--repeat", "N",
                        "a patch is re-observed (same ids) by up to N following keyframes")
            .fallback_text("the --regime's")
            .at_least(0)
            .at_most(1000),
        Option::number("--repeat-prob", "P", "probability of each re-observation")
            .fallback_text("the --regime's")
            .at_least(0)
            .at_most(1),
        Option::number("--depth-gain", "G",
                       "outlier rate and depth error grow as (depth / 3.5 m)^G")
            .fallback_text("the --regime's")
            .at_least(0)
            .at_most(10)},
       ""});
  return s;
}

/// The most `sim` writes: larger runs are refused before any work.
constexpr double kMaxSimOutputBytes = 1e9;

/// The bytes `sim` writes for n keyframes, estimated from its files: 6 kB of cloud per keyframe
/// (twice with --drift: truth/), and with --drift 150 bytes per row of the snapshots (one after
/// every tenth keyframe holding all keyframes so far, and the loop closure's: about n^2 / 20 rows).
double sim_output_bytes(std::size_t n, bool drift) {
  if (!drift) return 6e3 * double(n);
  const double every = double(sim::DriftParams{}.local_every), k = std::floor(double(n) / every);
  return 12e3 * double(n) + 150.0 * (every * k * (k + 1) / 2 + double(n));
}

sim::TreeSceneParams sim_params(const Args& args) {
  sim::Regime r;
  sim::find_regime(args.str("--regime"), r);
  sim::TreeSceneParams p = r.params;
  p.seed = static_cast<std::uint64_t>(args.integer("--seed"));
  p.keyframes = static_cast<std::size_t>(args.integer("--keyframes"));
  p.outliers = args.number("--outliers", p.outliers);
  p.outlier_cluster =
      static_cast<std::size_t>(args.integer("--cluster", static_cast<long>(p.outlier_cluster)));
  p.outlier_repeat =
      static_cast<std::size_t>(args.integer("--repeat", static_cast<long>(p.outlier_repeat)));
  p.repeat_prob = args.number("--repeat-prob", p.repeat_prob);
  p.outlier_depth_gain = args.number("--depth-gain", p.outlier_depth_gain);
  return p;
}

}  // namespace

const CommandSpec& sim_spec() {
  static const CommandSpec spec = make_sim_spec();
  return spec;
}

int run_sim(const Args& args) {
  const std::string out = args.str("--out");
  const sim::TreeSceneParams params = sim_params(args);
  const double bytes = sim_output_bytes(params.keyframes, args.has("--drift"));
  if (bytes > kMaxSimOutputBytes)
    throw UsageError("--keyframes " + std::to_string(params.keyframes) +
                     (args.has("--drift") ? " with --drift" : "") + " would write about " +
                     format_bytes(bytes) + ", more than the " + format_bytes(kMaxSimOutputBytes) +
                     " sim writes; use fewer keyframes");
  io::StagingDir stage(out);  // refuses a non-empty folder before any work; renamed at the end
  sim::TreeScene scene(params);
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
  const double drift = args.number("--drift", 0.0);
  const std::filesystem::path dir(stage.path());
  if (args.has("--drift")) {
    sim::DriftParams dp;
    dp.heading_drift = drift * M_PI / 180.0;
    dp.seed = scene.params().seed;
    const sim::DriftedRun run = sim::drift_run(poses, dp);
    io::write_sequence((dir / "truth").string(), poses, clouds);
    std::filesystem::create_directories(dir / "corrections");
    for (const auto& [after, snapshot] : run.snapshots) {
      char name[32];
      std::snprintf(name, sizeof name, "after_%06zu.txt", after);
      io::write_tum_poses((dir / "corrections" / name).string(), snapshot);
    }
    std::printf("drift %g corrections %zu max_offset_m %.3f\n", drift, run.snapshots.size(),
                run.max_offset);
    poses = run.tracked;
  }
  io::write_sequence(stage.path(), poses, clouds);
  eval::write_reference((dir / "reference.txt").string(), scene.reference());
  stage.commit();
  std::printf("keyframes %zu points %zu outliers %zu map_points %zu seen_once %.4f\n",
              keyframes.size(), points, outliers, distinct,
              sim::seen_once_fraction(keyframes, 4.0));
  return 0;
}

}  // namespace knnocc::cli
