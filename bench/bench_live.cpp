// bench_live: mapping under SLAM corrections (LiveMapper, include/knnocc/live/live_mapper.hpp).
// Prints the goals of the live-mapping work with what was measured:
//   1. per keyframe with live bookkeeping, ../shared/data/orbslam2_stereo_keyframes, k-NN model
//      (crop 4 m, 0.1 m): median ms of LiveMapper::add, against Mapper alone;
//   2. re-posing the last 10 keyframes, OctoMap model, simulated corridor of 500 / 2000 / 5000
//      keyframes: median ms, and the ratio 5000 / 500;
//   3. a loop closure that re-poses every keyframe against a from-scratch rebuild (both models);
//   4. memory per stored keyframe point;
//   5. drift injected into the stereo set's poses and corrected back by snapshots: the final
//      map (and tracker) equal the map of the original poses, checked here.
// Every timed map is also checked against a from-scratch Mapper once (exact: yes/NO).
//
// usage: bench_live [--data DIR] [--reps N]     (DIR default ../shared/data)

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <knnocc/io/sequence.hpp>
#include <knnocc/live/live_mapper.hpp>
#include <knnocc/map/same_voxels.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/sensor/knn_model.hpp>
#include <knnocc/sim/drift.hpp>
#include <knnocc/version.hpp>

#include "bench_common.hpp"

using namespace knnocc;
using bench::now;

namespace {

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// A from-scratch Mapper over the live mapper's keyframes, compared with it.
template <class Model, class Live>
bool exact(const Live& live, const Model& model, double res, const MapperOptions& o = {}) {
  Mapper<Model> m(res, model, o);
  std::vector<Point3d> world;
  for (const auto& kf : live.keyframes().frames()) {
    world.clear();
    for (const Point3f& p : kf.points)
      world.push_back(pose_traits<typename Live::pose_type>::to_world(kf.pose, p));
    const Point3d origin = pose_traits<typename Live::pose_type>::origin(kf.pose);
    if constexpr (Mapper<Model>::uses_map_cloud)
      m.insert_keyframe(origin, world, kf.ids);
    else
      m.insert_keyframe(origin, world);
  }
  bool same = same_voxels(live.map(), m.map());
  if constexpr (Mapper<Model>::uses_map_cloud)
    same = same && live.tracker().N() == m.tracker().N() &&
           live.tracker().mu() == m.tracker().mu() && live.tracker().sigma() == m.tracker().sigma();
  return same;
}

// ---- the stereo set ---------------------------------------------------------------------------

struct Keyframe {
  RigidPose pose;
  std::vector<Point3f> points;
  std::vector<std::uint64_t> ids;
};

RigidPose rigid(const io::Pose& p) {
  RigidPose r;
  const Eigen::Matrix3d m = p.q.toRotationMatrix();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.r[static_cast<std::size_t>(3 * i + j)] = m(i, j);
  r.t = {p.t.x(), p.t.y(), p.t.z()};
  return r;
}

std::vector<Keyframe> load_stereo(const std::string& dir, double crop,
                                  std::vector<io::Pose>& poses) {
  const auto seq = io::Sequence::open(dir);
  std::vector<Keyframe> out;
  for (std::size_t i = 0; i < seq.size(); ++i) {
    const io::Cloud c = seq.load_cloud(i);
    Keyframe kf;
    kf.pose = rigid(seq.pose(i));
    poses.push_back(seq.pose(i));
    for (std::size_t j = 0; j < c.points.size(); ++j) {
      const Point3f& p = c.points[j];
      if (!(std::sqrt(double(p.x) * p.x + double(p.y) * p.y + double(p.z) * p.z) <= crop)) continue;
      kf.points.push_back(p);
      kf.ids.push_back(c.ids.empty() ? j : c.ids[j]);
    }
    out.push_back(std::move(kf));
  }
  return out;
}

void stereo(const std::filesystem::path& dir, int reps) {
  if (!std::filesystem::exists(dir / "poses.txt")) {
    std::printf("\n[stereo set] SKIPPED: %s not found (pass --data)\n", dir.string().c_str());
    return;
  }
  std::vector<io::Pose> poses;
  const std::vector<Keyframe> kfs = load_stereo(dir.string(), 4.0, poses);
  const double res = 0.1;
  std::size_t points = 0;
  for (const auto& kf : kfs) points += kf.points.size();
  std::printf("\n[stereo set] %zu keyframes, %zu points within 4 m, k-NN model, %g m\n", kfs.size(),
              points, res);

  // 1. per keyframe, live against Mapper alone
  std::vector<double> live_ms, plain_ms;
  for (int r = 0; r < reps; ++r) {
    LiveMapper<KnnModel> live(res);
    Mapper<KnnModel> plain(res);
    std::vector<Point3d> world;
    for (std::size_t i = 0; i < kfs.size(); ++i) {
      double t = now();
      live.add(i, kfs[i].pose, kfs[i].points, kfs[i].ids);
      live_ms.push_back(1e3 * (now() - t));
      t = now();
      world.clear();
      for (const Point3f& p : kfs[i].points)
        world.push_back(pose_traits<RigidPose>::to_world(kfs[i].pose, p));
      plain.insert_keyframe(pose_traits<RigidPose>::origin(kfs[i].pose), world, kfs[i].ids);
      plain_ms.push_back(1e3 * (now() - t));
    }
    if (r == 0) {
      const double per_point = double(live.keyframe_memory()) / double(points);
      const double without_ids = per_point - double(sizeof(std::uint64_t));
      std::printf(
          "memory: %.1f bytes per stored keyframe point = %.1f (float xyz 12 + per-keyframe "
          "pose, box, index) + 8 (the id); goal <= 16 + ids: %s\n",
          per_point, without_ids, without_ids <= 16.0 ? "met" : "NOT met");
      // the k-NN model's cost of a correction: re-posing the last 10 keyframes rebuilds
      std::vector<double> fix_ms;
      for (int k = 0; k < 5; ++k) {
        std::vector<std::pair<std::uint64_t, RigidPose>> moved;
        for (std::size_t i = kfs.size() - 10; i < kfs.size(); ++i) {
          RigidPose p = kfs[i].pose;
          p.t[0] += 0.01 * (k % 2 ? -1 : 1);
          moved.emplace_back(i, p);
        }
        const double t = now();
        live.repose(moved);
        fix_ms.push_back(1e3 * (now() - t));
      }
      std::vector<double> scratch_ms;  // Mapper from scratch, the points moved into the world
      for (int k = 0; k < 5; ++k) {
        const double t = now();
        Mapper<KnnModel> m(res);
        std::vector<Point3d> w;
        for (const auto& kf : live.keyframes().frames()) {
          w.clear();
          for (const Point3f& p : kf.points)
            w.push_back(pose_traits<RigidPose>::to_world(kf.pose, p));
          m.insert_keyframe(pose_traits<RigidPose>::origin(kf.pose), w, kf.ids);
        }
        scratch_ms.push_back(1e3 * (now() - t));
      }
      std::printf(
          "k-NN model, re-posing the last 10 keyframes (a rebuild: mu and sigma change "
          "every later rating): median %.2f ms, a from-scratch Mapper %.2f ms (ratio "
          "%.2f; a loop closure costs the same); exact: %s\n",
          median(fix_ms), median(scratch_ms), median(fix_ms) / median(scratch_ms),
          exact(live, KnnModel{}, res) ? "yes" : "NO");
    }
  }
  const double lm = median(live_ms), pm = median(plain_ms);
  std::printf(
      "per keyframe with live bookkeeping: median %.3f ms (Mapper alone %.3f ms); goal <= "
      "1 ms: %s\n",
      lm, pm, lm <= 1.0 ? "met" : "NOT met");

  // 5. drift injected and corrected back, both models
  sim::DriftParams dp;
  dp.heading_drift = 0.05 * M_PI / 180.0;
  const sim::DriftedRun run = sim::drift_run(poses, dp);
  auto corrected = [&](auto model, const char* name) {
    using Model = decltype(model);
    LiveMapper<Model> live(res, model);
    std::vector<double> ms;
    std::size_t moved = 0;
    for (std::size_t i = 0; i < kfs.size(); ++i) {
      live.add(i, rigid(run.tracked[i]), kfs[i].points, kfs[i].ids);
      const auto s = run.snapshots.find(i);
      if (s == run.snapshots.end()) continue;
      std::vector<std::pair<std::uint64_t, RigidPose>> snap;
      for (std::size_t j = 0; j < s->second.size(); ++j) snap.emplace_back(j, rigid(s->second[j]));
      const double t = now();
      live.repose(snap);
      ms.push_back(1e3 * (now() - t));
      moved += live.last_update().changed;
    }
    // the oracle: the original poses, mapped from scratch
    Mapper<Model> truth(res, model);
    std::vector<Point3d> world;
    for (const auto& kf : kfs) {
      world.clear();
      for (const Point3f& p : kf.points)
        world.push_back(pose_traits<RigidPose>::to_world(kf.pose, p));
      const Point3d o = pose_traits<RigidPose>::origin(kf.pose);
      if constexpr (Mapper<Model>::uses_map_cloud)
        truth.insert_keyframe(o, world, kf.ids);
      else
        truth.insert_keyframe(o, world);
    }
    bool same = same_voxels(live.map(), truth.map());
    if constexpr (Mapper<Model>::uses_map_cloud)
      same = same && live.tracker().N() == truth.tracker().N() &&
             live.tracker().mu() == truth.tracker().mu() &&
             live.tracker().sigma() == truth.tracker().sigma();
    std::printf(
        "%s model: %zu corrections re-posed %zu keyframes, median %.2f ms, the loop "
        "closure %.2f ms; final map equals the map of the original poses: %s\n",
        name, ms.size(), moved, median(ms), ms.empty() ? 0.0 : ms.back(), same ? "yes" : "NO");
  };
  std::printf(
      "drift %.2f deg per keyframe injected (up to %.2f m off), corrected back by %zu "
      "snapshots:\n",
      dp.heading_drift * 180.0 / M_PI, run.max_offset, run.snapshots.size());
  corrected(OctoMapModel{}, "OctoMap");
  corrected(KnnModel{}, "k-NN");
}

// ---- the simulated corridor (OctoMap model) ---------------------------------------------------

// A sensor walking down a 3 m x 3 m corridor, 0.25 m per keyframe, seeing `n` wall, floor and
// ceiling points from 1 m behind to 4 m ahead: the map grows with the corridor while each
// keyframe's reach stays local, as in an exploring robot's sequence.
std::vector<Keyframe> corridor(std::size_t keyframes, std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Keyframe> out;
  for (std::size_t i = 0; i < keyframes; ++i) {
    Keyframe kf;
    kf.pose = RigidPose::yaw(0.02 * (u(rng) - 0.5), 0.25 * double(i), 0.0, 1.5);
    for (std::size_t j = 0; j < n; ++j) {
      const double x = -1.0 + 5.0 * u(rng), s = u(rng) * 4.0;
      double y, z;
      if (s < 1)
        y = -1.5, z = 3.0 * u(rng) - 1.5;  // left wall
      else if (s < 2)
        y = 1.5, z = 3.0 * u(rng) - 1.5;  // right wall
      else if (s < 3)
        z = -1.5, y = 3.0 * u(rng) - 1.5;  // floor
      else
        z = 1.5, y = 3.0 * u(rng) - 1.5;  // ceiling
      kf.points.push_back({float(x), float(y), float(z)});
    }
    out.push_back(std::move(kf));
  }
  return out;
}

void simulated(int reps) {
  const double res = 0.1;
  const std::size_t n = 1000;
  std::printf("\n[simulated corridor] OctoMap model, %g m, %zu points per keyframe, 0.25 m apart\n",
              res, n);
  const std::vector<Keyframe> all = corridor(5000, n, 7);
  double at500 = 0, at5000 = 0, at2000 = 0;
  for (const std::size_t count : {std::size_t{500}, std::size_t{2000}, std::size_t{5000}}) {
    LiveMapper<OctoMapModel> live(res);
    const double t0 = now();
    for (std::size_t i = 0; i < count; ++i) live.add(i, all[i].pose, all[i].points);
    const double build = now() - t0;
    std::vector<double> ms;
    std::size_t replayed = 0;
    for (int r = 0; r < std::max(reps, 5) * 3; ++r) {
      std::vector<std::pair<std::uint64_t, RigidPose>> moved;
      for (std::size_t i = count - 10; i < count; ++i) {
        RigidPose p = all[i].pose;
        p.t[1] += 0.03 * (r % 2 ? 1 : -1);
        moved.emplace_back(i, p);
      }
      const double t = now();
      live.repose(moved);
      ms.push_back(1e3 * (now() - t));
      replayed = live.last_update().replayed;
    }
    const double m = median(ms);
    (count == 500 ? at500 : count == 2000 ? at2000 : at5000) = m;
    if (count == 500)
      std::printf("memory: %.1f bytes per stored keyframe point (no ids: the OctoMap model)\n",
                  double(live.keyframe_memory()) / double(live.keyframes().points()));
    std::printf(
        "%5zu keyframes (built in %.2f s, map %zu voxels): re-posing the last 10 median "
        "%.2f ms (%zu keyframes replayed); exact: %s\n",
        count, build, live.map().num_voxels(), m, replayed,
        count == 500 && exact(live, OctoMapModel{}, res) ? "yes"
        : count == 500                                   ? "NO"
                                                         : "(checked at 500)");
    if (count == 2000) {  // 3. a loop closure that re-poses every keyframe
      std::vector<std::pair<std::uint64_t, RigidPose>> moved;
      for (std::size_t i = 0; i < count; ++i) {
        RigidPose p = all[i].pose;
        p.t[2] += 0.02;
        moved.emplace_back(i, p);
      }
      std::vector<double> loop_s, scratch_s;  // alternating, so both meet the same heap
      for (int r = 0; r < 3; ++r) {
        for (auto& mv : moved) mv.second.t[2] += 0.01;
        double t = now();
        live.repose(moved);
        loop_s.push_back(now() - t);
        t = now();
        live.rebuild();
        scratch_s.push_back(now() - t);
      }
      const double loop = median(loop_s), scratch = median(scratch_s);
      std::printf(
          "loop closure re-posing all 2000: %.3f s, from-scratch rebuild %.3f s: ratio "
          "%.2f (goal <= 1.2: %s)\n",
          loop, scratch, loop / scratch, loop / scratch <= 1.2 ? "met" : "NOT met");
    }
  }
  std::printf(
      "re-posing the last 10 at 2000 keyframes: %.2f ms (goal <= 5 ms: %s); 5000 / 500: "
      "%.2f (goal <= 1.5: %s)\n",
      at2000, at2000 <= 5.0 ? "met" : "NOT met", at5000 / at500,
      at5000 / at500 <= 1.5 ? "met" : "NOT met");
}

}  // namespace

int main(int argc, char** argv) {
  std::filesystem::path data = std::filesystem::path("..") / "shared" / "data";
  int reps = 3;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--data" && i + 1 < argc)
      data = argv[++i];
    else if (a == "--reps" && i + 1 < argc)
      reps = std::max(1, std::atoi(argv[++i]));
    else {
      std::fprintf(stderr, "usage: bench_live [--data DIR] [--reps N]\n");
      return 2;
    }
  }
  std::printf("bench_live: knnocc %s, build type '%s'\n", knnocc::version_string,
              KNNOCC_BENCH_BUILD_TYPE);
  stereo(data / "orbslam2_stereo_keyframes", reps);
  simulated(reps);
  std::printf("\npeak RSS: %.0f MB\n", bench::peak_rss_mb());
  return 0;
}
