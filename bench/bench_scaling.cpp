// bench_scaling: how insertion cost grows with the work, on fr079 scan.dat (88,206 points, one
// scan): time against resolution (the number of voxels per ray) and against max_range (the
// length of the rays), knnocc on 1 and 2 threads and liboctomap in the same run. The work
// measure is the ray keys (voxel visits, OctoMap's computeRayKeys) and the voxel updates.
//
// usage: bench_scaling [--repeat N] [--octomap-finest] [--data DIR]   (run from the project root)
//   liboctomap is skipped at 0.025 m (about 25 s) unless --octomap-finest.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "bench_common.hpp"

#include <knnocc/insertion/scan_inserter.hpp>
#include <knnocc/io/xyz.hpp>
#include <knnocc/version.hpp>

#if KNNOCC_HAVE_OCTOMAP
#include <octomap/OcTree.h>
#endif

namespace fs = std::filesystem;
using knnocc::OcKey;
using knnocc::Point3f;

namespace {

using knnocc::bench::now;
using knnocc::bench::scan_dat;

struct Run {
  double seconds = 1e30;
  std::size_t keys = 0, updates = 0;
};

Run knnocc_run(const std::vector<Point3f>& pts, double res, double range, unsigned threads,
               int repeat) {
  Run best;
  for (int r = 0; r < repeat; ++r) {
    knnocc::OccupancyMap<OcKey> map(res);
    knnocc::ScanInserter<OcKey> inserter(map, {}, threads);
    const double t0 = now();
    const auto st = inserter.insert_point_cloud(Point3f{}, pts, range);
    const double t = now() - t0;
    if (t < best.seconds) best = Run{t, st.ray_keys, st.occupied_voxels + st.free_voxels};
  }
  return best;
}

double octomap_run(const std::vector<Point3f>& pts, double res, double range) {
#if KNNOCC_HAVE_OCTOMAP
  return knnocc::bench::run_octomap({knnocc::bench::octomap_cloud(pts)}, {Point3f{}}, res, range)
      .seconds;
#else
  (void)pts, (void)res, (void)range;
  return 0.0;
#endif
}

void row(const char* label, const std::vector<Point3f>& pts, double res, double range, int repeat,
         bool with_octomap) {
  const Run one = knnocc_run(pts, res, range, 1, repeat);
  const Run two = knnocc_run(pts, res, range, 2, repeat);
  const double o = with_octomap ? octomap_run(pts, res, range) : 0.0;
  char oct[64] = "-", speedup[64] = "-";
  if (o > 0) {
    std::snprintf(oct, sizeof oct, "%.3f", o);
    std::snprintf(speedup, sizeof speedup, "%.0fx / %.0fx", o / one.seconds, o / two.seconds);
  }
  std::printf("| %-9s | %12zu | %11zu | %8.4f | %8.4f | %6.2f | %7.0f | %9s | %13s |\n", label,
              one.keys, one.updates, one.seconds, two.seconds, 1e9 * one.seconds / one.keys,
              one.keys / one.seconds / 1e6, oct, speedup);
}

void header(const char* first) {
  std::printf("| %-9s | %12s | %11s | %8s | %8s | %6s | %7s | %9s | %13s |\n", first, "ray keys",
              "updates", "1 thr s", "2 thr s", "ns/key", "Mkeys/s", "octomap s", "speed-up 1/2");
  std::printf("| --- | --- | --- | --- | --- | --- | --- | --- | --- |\n");
}

}  // namespace

int main(int argc, char** argv) {
  int repeat = 3;
  bool octomap_finest = false;
  fs::path data = fs::path("..") / "shared" / "data";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--repeat" && i + 1 < argc)
      repeat = std::max(1, std::atoi(argv[++i]));
    else if (a == "--octomap-finest")
      octomap_finest = true;
    else if (a == "--data" && i + 1 < argc)
      data = argv[++i];
    else {
      std::fprintf(stderr, "usage: bench_scaling [--repeat N] [--octomap-finest] [--data DIR]\n");
      return 2;
    }
  }
  const std::string dat = scan_dat(data);
  if (dat.empty()) {
    std::fprintf(stderr, "bench_scaling: no scan.dat under %s (run from the project root)\n",
                 data.string().c_str());
    return 2;
  }
  const auto pts = knnocc::io::read_xyz(dat).points;
  std::printf("bench_scaling: knnocc %s, build type '%s', %s; fr079 scan.dat, %zu points\n",
              knnocc::version_string, KNNOCC_BENCH_BUILD_TYPE,
#if KNNOCC_HAVE_OCTOMAP
              "liboctomap in the same run",
#else
              "liboctomap not found",
#endif
              pts.size());
#if KNNOCC_HAVE_OCTOMAP
  const bool have_octomap = true;
#else
  const bool have_octomap = false;
#endif

  std::printf("\nagainst resolution (no max range):\n\n");
  header("res");
  for (const double res : {0.4, 0.2, 0.1, 0.05, 0.025}) {
    char label[32];
    std::snprintf(label, sizeof label, "%g m", res);
    row(label, pts, res, -1.0, repeat, have_octomap && (res >= 0.05 || octomap_finest));
  }
  std::printf("\nagainst max range (res 0.1 m; farther points only free space up to it):\n\n");
  header("max range");
  for (const double range : {2.0, 5.0, 10.0, 20.0, -1.0}) {
    char label[32];
    if (range > 0)
      std::snprintf(label, sizeof label, "%g m", range);
    else
      std::snprintf(label, sizeof label, "none");
    row(label, pts, 0.1, range, repeat, have_octomap);
  }
  return 0;
}
