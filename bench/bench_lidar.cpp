// bench_lidar: a synthetic spinning LiDAR (64 beams x 1800 azimuths, 25 m range) on a moving
// vehicle, inserted with the OctoMap model by knnocc (1 and 2 threads) and, when found,
// liboctomap in the same run. Prints time per scan, ray keys (voxel visits) and map updates per
// second, and whether both libraries built the same map.
//
// The scene is analytic: a ground plane, box "buildings" and "cars", thin poles. Beams that hit
// nothing within 25 m get an end point at 30 m and are inserted with max_range 25 m (OctoMap's
// max-range semantics: free space up to 25 m, no occupied voxel).
//
// usage: bench_lidar [--scans N] [--res R] [--beams B] [--azimuths A] [--range M] [--repeat N]
//                    [--seed S] [--no-octomap]

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "bench_common.hpp"
#include "lidar_scene.hpp"

#include <knnocc/insertion/scan_inserter.hpp>
#include <knnocc/version.hpp>

#if KNNOCC_HAVE_OCTOMAP
#include <octomap/OcTree.h>
#endif

using knnocc::OcKey;
using knnocc::Point3f;

namespace {

using knnocc::bench::now;

using knnocc::bench::Scan;
using knnocc::bench::Scene;
using knnocc::bench::simulate;

struct Result {
  double seconds = 0;
  std::size_t keys = 0, updates = 0, occupied = 0, free = 0, bytes = 0;
};

Result run_knnocc(const std::vector<Scan>& scans, double res, double range, unsigned threads,
                  int repeat) {
  Result best;
  best.seconds = 1e30;
  for (int r = 0; r < repeat; ++r) {
    knnocc::OccupancyMap<OcKey> map(res);
    knnocc::ScanInserter<OcKey> inserter(map, {}, threads);
    Result res_now;
    const double t0 = now();
    for (const auto& s : scans) {
      const auto st = inserter.insert_point_cloud(s.origin, s.points, range);
      res_now.keys += st.ray_keys;
      res_now.updates += st.occupied_voxels + st.free_voxels;
    }
    res_now.seconds = now() - t0;
    if (res_now.seconds < best.seconds) {
      const auto c = map.count_voxels();
      res_now.occupied = c.occupied;
      res_now.free = c.free;
      res_now.bytes = map.memory_usage();
      best = res_now;
    }
  }
  return best;
}

#if KNNOCC_HAVE_OCTOMAP
Result run_octomap(const std::vector<Scan>& scans, double res, double range) {
  std::vector<octomap::Pointcloud> clouds;
  std::vector<Point3f> origins;
  for (const auto& scan : scans) {
    clouds.push_back(knnocc::bench::octomap_cloud(scan.points));
    origins.push_back(scan.origin);
  }
  const auto o = knnocc::bench::run_octomap(clouds, origins, res, range);
  Result r;
  r.seconds = o.seconds;
  r.occupied = o.occupied;
  r.free = o.free;
  r.bytes = o.bytes;
  return r;
}
#endif

}  // namespace

int main(int argc, char** argv) {
  int scans = 10, beams = 64, azimuths = 1800, repeat = 3;
  double res = 0.1, range = 25.0;
  unsigned seed = 1;
  bool octomap = true;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> const char* {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "bench_lidar: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--scans")
      scans = std::max(1, std::atoi(value()));
    else if (a == "--res")
      res = std::atof(value());
    else if (a == "--beams")
      beams = std::max(2, std::atoi(value()));
    else if (a == "--azimuths")
      azimuths = std::max(1, std::atoi(value()));
    else if (a == "--range")
      range = std::atof(value());
    else if (a == "--repeat")
      repeat = std::max(1, std::atoi(value()));
    else if (a == "--seed")
      seed = static_cast<unsigned>(std::atoi(value()));
    else if (a == "--no-octomap")
      octomap = false;
    else {
      std::fprintf(stderr,
                   "usage: bench_lidar [--scans N] [--res R] [--beams B] [--azimuths A] "
                   "[--range M] [--repeat N] [--seed S] [--no-octomap]\n");
      return 2;
    }
  }
  std::printf("bench_lidar: knnocc %s, build type '%s', %s\n", knnocc::version_string,
              KNNOCC_BENCH_BUILD_TYPE,
#if KNNOCC_HAVE_OCTOMAP
              "liboctomap in the same run");
#else
              "liboctomap not found (knnocc only)");
#endif
  const Scene scene(seed);
  const auto data = simulate(scene, scans, beams, azimuths, range, seed);
  std::size_t points = 0;
  for (const auto& s : data) points += s.points.size();
  std::printf(
      "%d scans of %d beams x %d azimuths (%zu points), max range %g m, res %g m, "
      "sensor moving 2 m per scan\n",
      scans, beams, azimuths, points, range, res);

  std::printf("%-22s %9s %11s %12s %12s %10s\n", "inserter", "s total", "ms per scan", "Mkeys/s",
              "Mupdates/s", "map MB");
  std::vector<Result> ours;
  for (const unsigned threads : {1u, 2u}) {
    const Result k = run_knnocc(data, res, range, threads, repeat);
    ours.push_back(k);
    const std::string name =
        "knnocc, " + std::to_string(threads) + " thread" + (threads > 1 ? "s" : "");
    std::printf("%-22s %9.3f %11.2f %12.1f %12.1f %10.1f\n", name.c_str(), k.seconds,
                1e3 * k.seconds / scans, k.keys / k.seconds / 1e6, k.updates / k.seconds / 1e6,
                k.bytes / 1e6);
  }
  std::printf("ray keys %zu, voxel updates %zu; map: occupied %zu free %zu\n", ours[0].keys,
              ours[0].updates, ours[0].occupied, ours[0].free);
#if KNNOCC_HAVE_OCTOMAP
  if (!octomap) return 0;
  const Result o = run_octomap(data, res, range);
  std::printf("%-22s %9.3f %11.2f %12.1f %12s %10.1f\n", "liboctomap", o.seconds,
              1e3 * o.seconds / scans, ours[0].keys / o.seconds / 1e6, "-", o.bytes / 1e6);
  const bool same = o.occupied == ours[0].occupied && o.free == ours[0].free &&
                    ours[1].occupied == ours[0].occupied && ours[1].free == ours[0].free;
  std::printf("speed-up: %.1fx (1 thread), %.1fx (2 threads); same map: %s\n",
              o.seconds / ours[0].seconds, o.seconds / ours[1].seconds,
              same ? "yes" : "NO, MAPS DIFFER");
#else
  (void)octomap;
#endif
  return 0;
}
