// bench_tracker: the k-NN tracker's incremental update against full recomputation.
//
//   1. A synthetic 1 M-point map cloud (noisy surfaces plus 1 % scattered outliers), then steps
//      of +1k new points and -1k removed points: time per step for ExactReverseKnn,
//      PaperAnnulus and a full recomputation (a fresh tracker over the whole cloud), whether
//      the exact s_p equal the recomputed ones bit for bit, and how many s_p PaperAnnulus left
//      stale. Memory per point.
//   2. The real ORB-SLAM2 stereo keyframes (ids, 4 m cut): microseconds per keyframe.
//
// usage: bench_tracker [--points N] [--steps S] [--k K] [--data DIR]   (run from the project root)

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>
#include <unordered_map>
#include <vector>

#include "bench_common.hpp"

#include <knnocc/io/sequence.hpp>
#include <knnocc/knn/tracker.hpp>
#include <knnocc/version.hpp>

namespace {

using knnocc::bench::now;

double peak_rss_mb() {
  struct rusage ru {};
  getrusage(RUSAGE_SELF, &ru);
  return ru.ru_maxrss / 1024.0;
}

// Points on a few hundred noisy planar patches and spheres (like a mapped scene), 1 % outliers.
class SceneSampler {
 public:
  explicit SceneSampler(std::uint64_t seed) : rng_(seed) {
    std::uniform_real_distribution<double> c(-50, 50);
    for (int i = 0; i < 300; ++i) centres_.push_back({c(rng_), c(rng_), c(rng_) * 0.2});
  }
  knnocc::Point3d sample() {
    if (u_(rng_) < 0.01) return {100 * u_(rng_) - 50, 100 * u_(rng_) - 50, 20 * u_(rng_) - 10};
    const auto& c =
        centres_[static_cast<std::size_t>(u_(rng_) * centres_.size()) % centres_.size()];
    if (u_(rng_) < 0.5) {  // a 4 m x 4 m patch, 1 cm noise
      return {c.x + 4 * u_(rng_) - 2, c.y + 4 * u_(rng_) - 2, c.z + 0.01 * g_(rng_)};
    }
    const double th = 2 * 3.14159265358979 * u_(rng_), z = 2 * u_(rng_) - 1;  // a 1.5 m sphere
    const double r = std::sqrt(1 - z * z);
    const double rad = 1.5 + 0.01 * g_(rng_);
    return {c.x + rad * r * std::cos(th), c.y + rad * r * std::sin(th), c.z + rad * z};
  }

 private:
  std::mt19937_64 rng_;
  std::uniform_real_distribution<double> u_{0.0, 1.0};
  std::normal_distribution<double> g_{0.0, 1.0};
  std::vector<knnocc::Point3d> centres_;
};

// Full recomputation as a non-incremental implementation would do it: one static KD-tree over
// the whole cloud, k-NN of every point, a two-pass mean and sigma. Returns s by id.
std::unordered_map<std::uint64_t, double> full_recompute(const std::vector<knnocc::IdPoint>& cloud,
                                                         std::size_t k,
                                                         knnocc::RunningNormal& dist) {
  knnocc::PointIndex index;
  for (const auto& ip : cloud) index.append(ip.id, ip.p);
  index.flush();  // large batch: builds the static tree
  std::unordered_map<std::uint64_t, double> s;
  s.reserve(cloud.size());
  std::vector<knnocc::Neighbor> nb;
  std::vector<double> valid;
  for (std::uint32_t i = 0; i < index.size(); ++i) {
    index.knn(i, k, nb);
    double sum = 0;
    for (const auto& n : nb) sum += std::sqrt(n.d2);
    const double si = nb.size() == k ? sum / double(k) : std::nan("");
    s[index.id(i)] = si;
    if (!std::isnan(si)) valid.push_back(si);
  }
  dist.recompute(valid);
  return s;
}

void synthetic(std::size_t n, int steps, std::size_t k) {
  std::printf("\n[1] synthetic cloud: %zu points, k = %zu, %d steps of +1000 / -1000 points\n", n,
              k, steps);
  SceneSampler scene(7);
  knnocc::ChangeSet initial;
  std::vector<knnocc::IdPoint> cloud;
  for (std::size_t i = 0; i < n; ++i) cloud.push_back({i, scene.sample()});
  initial.added = cloud;
  knnocc::TrackerParams params;
  params.k = k;
  knnocc::KnnTracker<> exact(params);
  knnocc::KnnTracker<knnocc::PaperAnnulus> paper(params, knnocc::PaperAnnulus{0.05, 1.0});
  double t0 = now();
  exact.apply(initial);
  const double build = now() - t0;
  paper.apply(initial);
  std::printf("initial build (tree + %zu k-NN queries): %.3f s; tracker memory %.0f bytes/point\n",
              n, build, double(exact.memory_usage()) / double(exact.size()));

  std::mt19937_64 rng(11);
  std::uint64_t next_id = n;
  double t_exact = 0, t_paper = 0, t_full = 0;
  std::size_t affected = 0, stale = 0, mismatched = 0;
  for (int s = 0; s < steps; ++s) {
    knnocc::ChangeSet cs;
    std::shuffle(cloud.begin(), cloud.end(), rng);
    for (int i = 0; i < 1000; ++i) {
      cs.removed.push_back(cloud.back().id);
      cloud.pop_back();
    }
    for (int i = 0; i < 1000; ++i) {
      cs.added.push_back({next_id++, scene.sample()});
      cloud.push_back(cs.added.back());
    }
    t0 = now();
    affected += exact.apply(cs).affected;
    t_exact += now() - t0;
    t0 = now();
    paper.apply(cs);
    t_paper += now() - t0;
    knnocc::RunningNormal full_dist;
    t0 = now();
    const auto full = full_recompute(cloud, k, full_dist);
    t_full += now() - t0;
    if (full_dist.count() != exact.N() ||
        std::fabs(full_dist.mean() - exact.mu()) > 1e-9 * full_dist.mean())
      ++mismatched;
    for (const auto& ip : cloud) {
      const double f = full.at(ip.id);
      mismatched += !(exact.s(ip.id) == f || (std::isnan(f) && std::isnan(exact.s(ip.id))));
      stale += !(paper.s(ip.id) == f || (std::isnan(f) && std::isnan(paper.s(ip.id))));
    }
  }
  std::printf("%-34s %12s %10s\n", "method", "ms / step", "speed-up");
  std::printf("%-34s %12.2f %9.0fx\n", "ExactReverseKnn (incremental)", 1e3 * t_exact / steps,
              t_full / t_exact);
  std::printf("%-34s %12.2f %9.0fx\n", "PaperAnnulus (dr 0.05, s_max 1 m)", 1e3 * t_paper / steps,
              t_full / t_paper);
  std::printf("%-34s %12.2f %9s\n", "full recomputation (static tree)", 1e3 * t_full / steps, "1x");
  std::printf(
      "exact: %zu affected points per step on average; every s_p, N and mu identical to full "
      "recomputation: %s (%zu differ)\n",
      affected / static_cast<std::size_t>(steps), mismatched ? "NO" : "yes", mismatched);
  std::printf("PaperAnnulus: %zu stale s_p summed over the steps\n", stale);
}

void orbslam(const std::filesystem::path& dir) {
  if (!std::filesystem::is_directory(dir)) {
    std::printf("\n[2] %s not found: skipped\n", dir.string().c_str());
    return;
  }
  const auto seq = knnocc::io::Sequence::open(dir.string());
  knnocc::TrackerParams params;
  params.k = 8;
  knnocc::KnnTracker<> tracker(params);
  std::vector<double> us;
  knnocc::KeyframeUnion map_cloud;
  std::vector<knnocc::Point3d> world;
  std::vector<std::uint64_t> ids;
  for (std::size_t i = 0; i < seq.size(); ++i) {
    knnocc::io::keyframe_to_world(seq.pose(i), seq.load_cloud(i), 4.0, world, ids);
    const knnocc::ChangeSet cs = map_cloud.add(world, ids);
    const double t0 = now();
    tracker.apply(cs);
    us.push_back(1e6 * (now() - t0));
  }
  std::vector<double> sorted = us;
  std::sort(sorted.begin(), sorted.end());
  std::printf(
      "\n[2] ORB-SLAM2 stereo keyframes (%zu, k = 8, 4 m cut): %zu map points; tracker "
      "update per keyframe: median %.0f us, 90th %.0f us, max %.0f us\n",
      us.size(), tracker.size(), sorted[sorted.size() / 2], sorted[sorted.size() * 9 / 10],
      sorted.back());
}

}  // namespace

int main(int argc, char** argv) {
  std::size_t points = 1000000, k = 10;
  int steps = 10;
  std::filesystem::path data = std::filesystem::path("..") / "shared" / "data";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--points" && i + 1 < argc)
      points = std::strtoull(argv[++i], nullptr, 10);
    else if (a == "--steps" && i + 1 < argc)
      steps = std::max(1, std::atoi(argv[++i]));
    else if (a == "--k" && i + 1 < argc)
      k = std::strtoull(argv[++i], nullptr, 10);
    else if (a == "--data" && i + 1 < argc)
      data = argv[++i];
    else {
      std::fprintf(stderr, "usage: bench_tracker [--points N] [--steps S] [--k K] [--data DIR]\n");
      return 2;
    }
  }
  std::printf("bench_tracker: knnocc %s, build type '%s', nanoflann 0x%x\n", knnocc::version_string,
              KNNOCC_BENCH_BUILD_TYPE, knnocc::detail::kNanoflannVersion);
  synthetic(points, steps, k);
  orbslam(data / "orbslam2_stereo_keyframes");
  std::printf("\npeak RSS: %.0f MB\n", peak_rss_mb());
  return 0;
}
