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

#include <knnocc/insertion/scan_inserter.hpp>
#include <knnocc/version.hpp>

#if KNNOCC_HAVE_OCTOMAP
#include <octomap/OcTree.h>
#endif

using knnocc::OcKey;
using knnocc::Point3f;

namespace {

using knnocc::bench::now;

struct Box {
  double lo[3], hi[3];
};

// Slab test: distance along the unit direction d from o to the box, or a negative number.
double hit_box(const Box& b, const double o[3], const double d[3]) {
  double t0 = 0.0, t1 = 1e30;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0) {
      if (o[a] < b.lo[a] || o[a] > b.hi[a]) return -1.0;
      continue;
    }
    double ta = (b.lo[a] - o[a]) / d[a], tb = (b.hi[a] - o[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return -1.0;
  }
  return t0 > 0.0 ? t0 : -1.0;
}

struct Scene {
  std::vector<Box> boxes;

  explicit Scene(unsigned seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    // Buildings along both sides of a 300 m street (y in [-8, 8] is the road).
    for (double x = -40; x < 300; x += 12 + 10 * u(rng)) {
      for (const double side : {-1.0, 1.0}) {
        const double y0 = side * (9 + 4 * u(rng)), depth = 8 + 10 * u(rng);
        const double w = 6 + 6 * u(rng), h = 4 + 12 * u(rng);
        boxes.push_back(
            {{x, std::min(y0, y0 + side * depth), 0}, {x + w, std::max(y0, y0 + side * depth), h}});
      }
    }
    // Parked cars and poles.
    for (double x = -40; x < 300; x += 5 + 15 * u(rng)) {
      const double y = (u(rng) < 0.5 ? -1 : 1) * (5.5 + 1.5 * u(rng));
      boxes.push_back({{x, y - 0.9, 0}, {x + 4.3, y + 0.9, 1.5}});
      const double py = (u(rng) < 0.5 ? -1 : 1) * 8.3;
      boxes.push_back({{x + 2, py - 0.1, 0}, {x + 2.2, py + 0.1, 6}});
    }
  }

  // Range to the first surface along the unit direction d, or a negative number.
  double cast(const double o[3], const double d[3]) const {
    double best = d[2] < 0 ? -o[2] / d[2] : -1.0;  // ground z = 0
    for (const Box& b : boxes) {
      const double t = hit_box(b, o, d);
      if (t > 0 && (best < 0 || t < best)) best = t;
    }
    return best;
  }
};

using knnocc::bench::Scan;

std::vector<Scan> simulate(const Scene& scene, int scans, int beams, int azimuths, double range,
                           unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<Scan> out;
  for (int s = 0; s < scans; ++s) {
    Scan scan;
    const double o[3] = {2.0 * s, 0.3 * std::sin(0.3 * s), 1.8};  // 2 m between scans
    scan.origin = {float(o[0]), float(o[1]), float(o[2])};
    for (int b = 0; b < beams; ++b) {
      const double elev = (-24.9 + (2.0 + 24.9) * b / (beams - 1)) * M_PI / 180.0;  // HDL-64
      for (int a = 0; a < azimuths; ++a) {
        const double az = 2 * M_PI * (a + 0.5 * (b % 2)) / azimuths;
        const double d[3] = {std::cos(elev) * std::cos(az), std::cos(elev) * std::sin(az),
                             std::sin(elev)};
        double r = scene.cast(o, d);
        if (r < 0 || r > range)
          r = range + 5.0;  // no return: beyond the max range
        else
          r += noise(rng);
        scan.points.push_back(
            {float(o[0] + r * d[0]), float(o[1] + r * d[1]), float(o[2] + r * d[2])});
      }
    }
    out.push_back(std::move(scan));
  }
  return out;
}

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
