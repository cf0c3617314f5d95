// knnocc sim: writes a simulated scene as a sequence folder: the tree scene of the paper's
// experiment (the default), or with --scene drive a long LiDAR drive through a city.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include <knnocc/eval/reference.hpp>
#include <knnocc/io/ply.hpp>
#include <knnocc/io/sequence.hpp>
#include <knnocc/sim/drift.hpp>
#include <knnocc/sim/drive_scene.hpp>
#include <knnocc/sim/regimes.hpp>
#include <knnocc/sim/tree_scene.hpp>

#include "args.hpp"
#include "commands.hpp"
#include "output_set.hpp"
#include "progress.hpp"
#include "resource_limits.hpp"

namespace knnocc::cli {

namespace {

// The flags that override the --regime's wrong matches and features.
void add_regime_groups(CommandSpec& s) {
  const sim::TreeSceneParams p;
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
  s.groups.push_back(
      {"features (override --regime)",
       {Option::number("--detect", "P",
                       "probability that a keyframe observes a feature it sees (the mean over "
                       "features with --detect-spread)")
            .fallback_text(format_number(p.detect) + ", or the --regime's")
            .above(0)
            .at_most(1),
        Option::number("--detect-spread", "S",
                       "each feature its own detection probability: --detect times a log-normal "
                       "factor of mean 1 and log-sd S (at most 1)")
            .fallback_text("0, or the --regime's")
            .at_least(0)
            .at_most(3)},
       ""});
}

// The options of the drive scene.
void add_drive_group(CommandSpec& s) {
  const sim::DriveSceneParams d;
  s.groups.push_back(
      {"drive scene (--scene drive)",
       {Option::integer("--scans", "N", "scans, one every --spacing metres of road")
            .fallback(std::to_string(d.scans))
            .at_least(1)
            .at_most(100000),
        Option::number("--spacing", "M", "metres of road between scans")
            .fallback(format_number(d.spacing))
            .at_least(0.1)
            .at_most(100),
        Option::integer("--columns", "C", "firings per revolution of the LiDAR")
            .fallback(std::to_string(d.columns))
            .at_least(8)
            .at_most(36000),
        Option::integer("--beams", "B",
                        "lasers: the upper half evenly from +2 to -8.33 degrees, the lower half "
                        "from -8.83 to -24.8 (HDL-64E-like)")
            .fallback(std::to_string(d.beams))
            .at_least(2)
            .at_most(256)},
       ""});
}

/// The options that only one scene takes.
constexpr const char* kDriveOnly[] = {"--scans", "--spacing", "--columns", "--beams"};
constexpr const char* kTreeOnly[] = {
    "--keyframes", "--outliers",    "--drift",      "--regime", "--cluster",
    "--repeat",    "--repeat-prob", "--depth-gain", "--detect", "--detect-spread"};

void check_scene_options(const Args& args, bool drive) {
  if (drive) {
    for (const char* o : kTreeOnly)
      if (args.has(o)) throw UsageError(std::string(o) + " applies to --scene tree only");
  } else {
    for (const char* o : kDriveOnly)
      if (args.has(o)) throw UsageError(std::string(o) + " needs --scene drive");
  }
}

/// What `--help` says about the drive scene.
constexpr const char* kDriveText =
    R"(--scene drive: a car with a spinning LiDAR (64 beams from +2 to -24.8 degrees, 1,800 columns,
80 m, 1.73 m above the ground) drives 8.4 km through a grid of city blocks (20-30 m roads,
buildings, street trees, poles, parked and moving cars), turning at crossings, one scan every
4 m; its route reaches 5-8 km east of the start, beyond OctoMap's key range at 0.1 m. Range
noise (5.9 mm) and missing returns (0.34 %) are measured on the real scan of
../shared/data/octomap_fr079 (docs/drive_scene.md). Writes
  DIR/poses.txt, DIR/clouds/NNNNNN.ply   sensor-to-world poses (TUM) and clouds (sensor frame,
                                         float x y z), for `knnocc map --input DIR --res 0.1 ...`
and prints: scans N points N route_m M extent_m X Y Z seconds S
(route_m: road between the first and the last scan; extent_m: the points' bounding box in the
world). The default drive takes about 40 s on one core and writes 2.8 GB (234 million points);
a drive is refused before any work when it could write more than the free space beside DIR (12
bytes per beam).
)";

CommandSpec make_sim_spec() {
  const sim::TreeSceneParams p;
  CommandSpec s;
  s.name = "sim";
  s.summary =
      "write a simulated scene as a sequence folder: the paper's tree scene and its reference "
      "shapes, or a long LiDAR drive through a city (--scene drive)";
  s.usage =
      "knnocc sim --out DIR [--seed S] [--keyframes N] [--outliers F] [--drift DEG]\n"
      "                  [--regime NAME] [--cluster N] [--repeat N] [--repeat-prob P] "
      "[--depth-gain G]\n"
      "                  [--detect P] [--detect-spread S]\n"
      "       knnocc sim --scene drive --out DIR [--seed S] [--scans N] [--spacing M] "
      "[--columns C]\n"
      "                  [--beams B]";
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
complete, so a failed run leaves no partial folder. A tree-scene run whose output would exceed
1 GB is refused before any work (with --drift the snapshots grow with the square of --keyframes:
10,000 keyframes write about 0.9 GB).

)";
  s.text += kDriveText;
  s.groups.push_back(
      {"options",
       {Option::text("--out", "DIR", "the sequence folder to write").alias("-o").required(),
        Option::integer("--seed", "S", "random seed; the same scene for a seed with this build")
            .fallback("1")
            .at_least(0),
        Option::integer("--keyframes", "N", "keyframes around the circle")
            .fallback_text(std::to_string(p.keyframes) + ", or the --regime's")
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
            .one_of({"isolated", "clustered", "repeated", "realistic"}),
        Option::text("--scene", "NAME",
                     "tree: the paper's tree scene; drive: a long LiDAR drive (options below)")
            .fallback("tree")
            .one_of({"tree", "drive"})},
       ""});
  add_regime_groups(s);
  add_drive_group(s);
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
  p.keyframes =
      static_cast<std::size_t>(args.integer("--keyframes", static_cast<long>(p.keyframes)));
  p.detect = args.number("--detect", p.detect);
  p.detect_spread = args.number("--detect-spread", p.detect_spread);
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

namespace {

/// The world-frame bounding box of points.
struct Extent {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(HUGE_VAL), hi = -lo;
  void add(const io::Pose& pose, const std::vector<Point3f>& pts) {
    const Eigen::Matrix3d R = pose.q.toRotationMatrix();
    for (const Point3f& p : pts) {
      const Eigen::Vector3d w = R * Eigen::Vector3d(p.x, p.y, p.z) + pose.t;
      lo = lo.cwiseMin(w);
      hi = hi.cwiseMax(w);
    }
  }
  Eigen::Vector3d size() const {
    return lo.x() <= hi.x() ? Eigen::Vector3d(hi - lo) : Eigen::Vector3d::Zero();
  }
};

sim::DriveSceneParams drive_params(const Args& args) {
  sim::DriveSceneParams p;
  p.seed = static_cast<std::uint64_t>(args.integer("--seed"));
  p.scans = static_cast<std::size_t>(args.integer("--scans"));
  p.spacing = args.number("--spacing");
  p.columns = static_cast<int>(args.integer("--columns"));
  p.beams = static_cast<int>(args.integer("--beams"));
  if (p.route_length() > 200000)
    throw UsageError("--scans " + std::to_string(p.scans) + " every --spacing " +
                     format_number(p.spacing) + " m is more than the 200 km of road sim drives");
  return p;
}

/// Refuses a drive that could fill the disk: 12 bytes per beam, against the free space beside
/// the output folder.
void check_drive_space(const sim::DriveSceneParams& p, const std::string& out) {
  const double most =
      12.0 * double(p.scans) * double(p.beams) * double(p.columns) + 200.0 * p.scans;
  std::filesystem::path target = std::filesystem::absolute(out);
  if (!target.has_filename()) target = target.parent_path();  // "out/" -> "out"
  const std::filesystem::path parent = target.parent_path();
  std::error_code ec;
  const std::filesystem::space_info space = std::filesystem::space(parent, ec);
  if (!ec && most > double(space.available))
    throw UsageError("the drive could write " + format_bytes(most) +
                     " (12 bytes per beam), more "
                     "than the " +
                     format_bytes(double(space.available)) + " free in " + parent.string() +
                     "; use fewer --scans, --columns or --beams");
}

int run_drive(const Args& args) {
  const auto start = std::chrono::steady_clock::now();
  const std::string out = args.str("--out");
  const sim::DriveSceneParams params = drive_params(args);
  check_drive_space(params, out);
  io::StagingDir stage(out);  // refuses a non-empty folder before any work; renamed at the end
  const std::filesystem::path dir(stage.path());
  std::filesystem::create_directories(dir / "clouds");
  const sim::DriveScene scene(params);
  Progress progress("sim drive", params.scans);
  std::vector<io::Pose> poses;
  std::size_t points = 0;
  Extent extent;
  for (std::size_t i = 0; i < params.scans; ++i) {
    const sim::DriveScan scan = scene.scan(i);
    char name[32];
    std::snprintf(name, sizeof name, "%06zu.ply", i);
    io::write_ply((dir / "clouds" / name).string(), scan.cloud.points);
    poses.push_back(scan.pose);
    points += scan.cloud.points.size();
    extent.add(scan.pose, scan.cloud.points);
    progress.update(i + 1);
  }
  io::write_tum_poses((dir / "poses.txt").string(), poses);  // last: a complete sequence
  stage.commit();
  progress.finish();
  const Eigen::Vector3d size = extent.size();
  std::printf("scans %zu points %zu route_m %.1f extent_m %.1f %.1f %.1f seconds %.1f\n",
              params.scans, points, params.route_length(), size.x(), size.y(), size.z(),
              std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return 0;
}

}  // namespace

int run_sim(const Args& args) {
  const bool drive = args.str("--scene") == "drive";
  check_scene_options(args, drive);
  if (drive) return run_drive(args);
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
