// bench_bonxai_memory: peak memory per known voxel, knnocc against Bonxai's ProbabilisticMap, on
// the same clouds, origins and resolution. Built only when CMake is given -DKNNOCC_BONXAI_DIR=<a
// Bonxai checkout> (bench/NOTES.md).
//
// usage: bench_bonxai_memory [--data DIR]   (DIR defaults to ../shared/data; run from the root)
//
// Workloads: scan.dat (one scan of octomap_fr079, as bench_insert) at 0.1 and 0.05 m, the ten TUM
// fr2/pioneer_slam2 clouds at 0.05 m, and bench_lidar's sweep (10 scans of 64 beams x 1800
// azimuths, max range 25 m) at 0.1 m. Each library inserts a workload in its own forked child;
// the figure is the peak resident memory the insertion added to the child (its peak reset at the
// start, the clouds inherited from the parent not counted). Known voxels: knnocc's
// OccupancyMap::num_voxels(); Bonxai's cells holding a value (VoxelGrid::activeCellsCount()).
// knnocc walks rays exactly (every voxel a ray crosses, as OctoMap); Bonxai steps one voxel per
// longest axis, so it knows fewer free voxels for the same clouds: hence per known voxel.

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "bench_common.hpp"
#include "lidar_scene.hpp"

#include <bonxai_map/probabilistic_map.hpp>
#include <knnocc/insertion/scan_inserter.hpp>
#include <knnocc/io/xyz.hpp>
#include <knnocc/version.hpp>

namespace fs = std::filesystem;
using knnocc::bench::Scan;

namespace {

struct Workload {
  std::string name;
  const std::vector<Scan>* scans;
  double res, max_range;  // max_range < 0: none
};

struct Measure {
  double added_mb = 0, seconds = 0, structure_mb = 0;
  std::size_t known = 0;
  // knnocc only: the inserter's scratch by part (ScanInserter::scratch_usage), the resident memory
  // at the end with and without the inserter (the map alone), all relative to the start.
  knnocc::ScratchUsage scratch;
  double end_mb = 0, map_mb = 0;
};

// Runs f() (which fills known, seconds and structure_mb) in a forked child; adds the peak RSS the
// child gained over what it started with.
template <class F>
Measure in_child(F f) {
  auto [m, added_mb] = knnocc::bench::in_child(f);
  m.added_mb = added_mb;
  return m;
}

Measure run_knnocc(const Workload& w) {
  const double start_mb = knnocc::bench::resident_mb();
  knnocc::OccupancyMap<knnocc::OcKey> map(w.res);
  Measure m;
  {
    knnocc::ScanInserter<knnocc::OcKey> inserter(map);
    const double t0 = knnocc::bench::now();
    for (const Scan& s : *w.scans) inserter.insert_point_cloud(s.origin, s.points, w.max_range);
    m.seconds = knnocc::bench::now() - t0;
    m.scratch = inserter.scratch_usage();
    m.end_mb = knnocc::bench::resident_mb() - start_mb;
  }
  malloc_trim(0);
  m.map_mb = knnocc::bench::resident_mb() - start_mb;
  m.known = map.num_voxels();
  m.structure_mb = static_cast<double>(map.memory_usage()) / 1e6;
  return m;
}

// Where knnocc's peak went: the map, and the inserter's scratch kept between scans, by part.
void print_parts(const Measure& m) {
  const knnocc::ScratchUsage& u = m.scratch;
  auto mb = [](std::size_t b) { return static_cast<double>(b) / 1048576.0; };
  std::printf(
      "%-26s   resident at end %.1f MB: map %.1f, inserter %.1f; inserter scratch held %.1f MB: "
      "hit bitmaps %.2f, miss bitmaps %.2f, point buffers %.2f, ray blocks %.2f, hashed %.2f, "
      "brick groups %.2f, other %.2f\n",
      "", m.end_mb, m.map_mb, m.end_mb - m.map_mb, mb(u.total()), mb(u.hit_bitmaps),
      mb(u.miss_bitmaps), mb(u.point_buffers), mb(u.ray_blocks), mb(u.hashed), mb(u.brick_groups),
      mb(u.other));
}

Measure run_bonxai(const Workload& w) {
  Bonxai::ProbabilisticMap map(w.res);
  const double range = w.max_range > 0 ? w.max_range : std::numeric_limits<double>::max();
  const double t0 = knnocc::bench::now();
  for (const Scan& s : *w.scans) map.insertPointCloud(s.points, s.origin, range);
  Measure m;
  m.seconds = knnocc::bench::now() - t0;
  m.known = map.grid().activeCellsCount();
  m.structure_mb = static_cast<double>(map.grid().memUsage()) / 1e6;
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  fs::path data = fs::path("..") / "shared" / "data";
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--data" && i + 1 < argc) {
      data = argv[++i];
    } else {
      std::fprintf(stderr, "usage: bench_bonxai_memory [--data DIR]\n");
      return 2;
    }
  }
  std::printf("bench_bonxai_memory: knnocc %s, build type '%s', Bonxai ProbabilisticMap\n",
              knnocc::version_string, KNNOCC_BENCH_BUILD_TYPE);
  std::vector<Scan> scan_dat, tum;
  if (const std::string p = knnocc::bench::scan_dat(data); !p.empty())
    scan_dat.push_back(Scan{knnocc::Point3f{}, knnocc::io::read_xyz(p).points});
  if (fs::is_directory(data / "tum_fr2_pioneer_slam2"))
    tum = knnocc::bench::sequence_scans((data / "tum_fr2_pioneer_slam2").string());
  const knnocc::bench::Scene scene(1);
  const std::vector<Scan> lidar = knnocc::bench::simulate(scene, 10, 64, 1800, 25.0, 1);

  std::vector<Workload> loads;
  if (!scan_dat.empty()) {
    loads.push_back({"scan.dat 0.1 m", &scan_dat, 0.1, -1.0});
    loads.push_back({"scan.dat 0.05 m", &scan_dat, 0.05, -1.0});
  } else {
    std::printf("scan.dat: not found under %s, skipped\n", data.string().c_str());
  }
  if (!tum.empty())
    loads.push_back({"TUM pioneer_slam2 0.05 m", &tum, 0.05, -1.0});
  else
    std::printf("TUM fr2/pioneer_slam2: not found under %s, skipped\n", data.string().c_str());
  loads.push_back({"LiDAR 10 x 64x1800 0.1 m", &lidar, 0.1, 25.0});

  std::printf("%-26s %-7s %12s %10s %9s %12s %12s %8s\n", "workload", "library", "known voxels",
              "peak MB", "s", "B/known", "struct MB", "ours/bx");
  for (const Workload& w : loads) {
    const Measure ours = in_child([&] { return run_knnocc(w); });
    const Measure bx = in_child([&] { return run_bonxai(w); });
    const double ours_b = ours.added_mb * 1048576.0 / static_cast<double>(ours.known);
    const double bx_b = bx.added_mb * 1048576.0 / static_cast<double>(bx.known);
    std::printf("%-26s %-7s %12zu %10.1f %9.3f %12.1f %12.1f\n", w.name.c_str(), "knnocc",
                ours.known, ours.added_mb, ours.seconds, ours_b, ours.structure_mb);
    print_parts(ours);
    std::printf("%-26s %-7s %12zu %10.1f %9.3f %12.1f %12.1f %8.2f%s\n", "", "Bonxai", bx.known,
                bx.added_mb, bx.seconds, bx_b, bx.structure_mb, ours_b / bx_b,
                ours_b <= bx_b ? "" : "  (knnocc needs more per known voxel)");
  }
  std::printf(
      "peak MB: resident memory the insertion added to its forked child; B/known: that per known "
      "voxel;\nstruct MB: the map's own estimate (OccupancyMap::memory_usage, "
      "VoxelGrid::memUsage); "
      "ours/bx: ratio of B/known\n");
  return 0;
}
