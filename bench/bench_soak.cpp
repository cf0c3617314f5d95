// bench_soak: a long run of the k-NN mapper. The simulated tree scene (knnocc demo's) goes on
// circling for 10,000 keyframes while the map point cloud changes as in a SLAM system: new map
// points join on first sight, wrong matches are culled after 5 keyframes, 1 % of the other
// points are culled and 2 % moved (bundle adjustment) per keyframe, culled points rejoin when
// seen again. Prints, at checkpoints, resident memory, map and tracker sizes, and whether every
// s_p, N, mu and sigma still equal a brute-force computation over the map point cloud.
//
//   build/bin/bench_soak [--keyframes N] [--check-every M] [--seed S]

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include <knnocc/mapper.hpp>
#include <knnocc/sensor/knn_model.hpp>
#include <knnocc/sim/tree_scene.hpp>

#include "../tests/knn_truth.hpp"
#include "bench_common.hpp"

using namespace knnocc;

namespace {

// The map point cloud as the SLAM system sees it, with O(1) random picks.
struct Cloud {
  std::unordered_map<std::uint64_t, Point3d> pos;
  std::vector<std::uint64_t> ids;
  std::unordered_map<std::uint64_t, std::size_t> slot;
  void add(std::uint64_t id, const Point3d& p) {
    pos[id] = p;
    slot[id] = ids.size();
    ids.push_back(id);
  }
  void remove(std::uint64_t id) {
    const std::size_t s = slot.at(id);
    slot[ids.back()] = s;
    ids[s] = ids.back();
    ids.pop_back();
    slot.erase(id);
    pos.erase(id);
  }
};

}  // namespace

int main(int argc, char** argv) {
  long keyframes = 10000, every = 1000, seed = 1;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--keyframes")) keyframes = std::atol(argv[i + 1]);
    if (!std::strcmp(argv[i], "--check-every")) every = std::atol(argv[i + 1]);
    if (!std::strcmp(argv[i], "--seed")) seed = std::atol(argv[i + 1]);
  }
  if (keyframes < 1 || every < 1) {
    std::fprintf(stderr, "usage: bench_soak [--keyframes N] [--check-every M] [--seed S]\n");
    return 2;
  }
  std::printf(
      "bench_soak (%s build): %ld keyframes of the simulated tree scene, k-NN model, "
      "0.1 m, 4 m crop, seed %ld\n",
      KNNOCC_BENCH_BUILD_TYPE, keyframes, seed);
  sim::TreeSceneParams sp;
  sp.seed = static_cast<std::uint64_t>(seed);
  sp.keyframes = 100;  // per circle
  sim::TreeScene scene(sp);
  const KnnModel model;
  Mapper<KnnModel> mapper(0.1, model);
  Cloud cloud;
  std::unordered_map<std::uint64_t, long> outlier_born;
  std::mt19937_64 rng(static_cast<std::uint64_t>(seed) * 7919);
  std::normal_distribution<double> jitter(0.0, 0.01);
  std::vector<Point3d> world;
  std::vector<std::uint64_t> ids;
  std::size_t added = 0, removed = 0, moved = 0, checks_failed = 0;
  double first_rss = 0, max_rss = 0, ms_total = 0;
  std::printf("%9s %10s %10s %11s %12s %10s %9s %s\n", "keyframe", "map_points", "voxels", "map_MB",
              "tracker_MB", "RSS_MB", "ms/kf", "brute force");
  const double t0 = bench::now();
  for (long f = 1; f <= keyframes; ++f) {
    const sim::SimKeyframe kf = scene.next();
    io::keyframe_to_world(kf.pose, kf.cloud, 4.0, world, ids);
    ChangeSet cs;
    std::unordered_set<std::uint64_t> touched;
    for (std::size_t j = 0; j < ids.size(); ++j) {
      if (cloud.pos.count(ids[j]) || !touched.insert(ids[j]).second) continue;
      cs.added.push_back({ids[j], world[j]});
      if (ids[j] >= sim::TreeScene::kOutlierIdBase) outlier_born[ids[j]] = f;
    }
    for (auto it = outlier_born.begin(); it != outlier_born.end();) {  // cull old wrong matches
      if (f - it->second < 5) {
        ++it;
        continue;
      }
      if (cloud.pos.count(it->first) && touched.insert(it->first).second)
        cs.removed.push_back(it->first);
      it = outlier_born.erase(it);
    }
    const std::size_t n = cloud.ids.size();
    for (std::size_t c = 0; c < n / 100 && n; ++c) {  // culling
      const std::uint64_t id = cloud.ids[rng() % n];
      if (touched.insert(id).second) cs.removed.push_back(id);
    }
    for (std::size_t c = 0; c < n / 50 && n; ++c) {  // bundle adjustment
      const std::uint64_t id = cloud.ids[rng() % n];
      if (!touched.insert(id).second) continue;
      const Point3d& p = cloud.pos.at(id);
      cs.moved.push_back({id, {p.x + jitter(rng), p.y + jitter(rng), p.z + jitter(rng)}});
    }
    for (const std::uint64_t id : cs.removed) cloud.remove(id);
    for (const IdPoint& m : cs.moved) cloud.pos[m.id] = m.p;
    for (const IdPoint& a : cs.added) cloud.add(a.id, a.p);
    added += cs.added.size();
    removed += cs.removed.size();
    moved += cs.moved.size();

    const double a = bench::now();
    mapper.insert_keyframe(kf.pose.t, world, ids, cs);
    ms_total += (bench::now() - a) * 1000;

    const double rss = bench::resident_mb();
    max_rss = std::max(max_rss, rss);
    if (f % every == 0 || f == keyframes) {
      if (first_rss == 0) first_rss = rss;
      test::Cloud truth_cloud(cloud.pos.begin(), cloud.pos.end());
      const test::Truth t =
          test::brute_force(truth_cloud, model.params().k, model.params().s_limit);
      const auto& tr = mapper.tracker();
      std::size_t wrong = tr.size() != truth_cloud.size();
      for (const auto& [id, p] : truth_cloud) {
        const double s = tr.s(id), e = t.s.at(id);
        wrong += !(s == e || (std::isnan(s) && std::isnan(e)));
      }
      const double scale = std::max({std::fabs(t.mean), t.sigma, 1e-12});
      wrong += tr.N() != t.n || !(std::fabs(tr.mu() - t.mean) <= 1e-9 * scale) ||
               !(std::fabs(tr.sigma() - t.sigma) <= 1e-9 * scale);
      checks_failed += wrong != 0;
      std::printf("%9ld %10zu %10zu %11.2f %12.2f %10.1f %9.3f %s\n", f, tr.size(),
                  mapper.map().num_voxels(), mapper.map().memory_usage() / 1048576.0,
                  tr.memory_usage() / 1048576.0, rss, ms_total / static_cast<double>(f),
                  wrong ? "DIFFERS" : "equal");
    }
  }
  std::printf(
      "\nchange sets: %zu added, %zu removed, %zu moved; RSS %.1f MB at the first checkpoint, "
      "%.1f MB at most; %zu checkpoint(s) differing from brute force; %.1f s\n",
      added, removed, moved, first_rss, max_rss, checks_failed, bench::now() - t0);
  return checks_failed ? 1 : 0;
}
