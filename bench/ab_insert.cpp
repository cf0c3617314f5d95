// ab_insert: the OctoMap-model insertion with two versions of knnocc in one process, run after
// run in turn, so that both meet the same spells of a noisy machine (bench_insert's same-run
// ratios against liboctomap move by 20-40% from one run to the next here; a 5% change in knnocc
// only shows this way). Built and run by bench/ab_insert.sh, which puts an earlier revision's
// headers in namespace knnocc_old beside the working tree's.
//
// usage (through the script): ab_insert THREADS PAIRS RES DATA
//   DATA: a TUM-style sequence directory, or an xyz file (scan.dat) inserted from the origin.
// Prints each version's best time, the ratio of the bests and the median ratio over the pairs
// (new / old: below 1 is faster), and checks that both built the same map.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench_common.hpp"

#include <knnocc/insertion/scan_inserter.hpp>
#include <knnocc/io/xyz.hpp>
// The earlier revision's inserter, wherever that revision kept it.
#if __has_include(<knnocc_old/insertion/scan_inserter.hpp>)
#include <knnocc_old/insertion/scan_inserter.hpp>
#else
#include <knnocc_old/map/scan_inserter.hpp>
#endif

namespace {

using knnocc::bench::now;
using knnocc::bench::Scan;

std::vector<Scan> load(const std::string& data) {
  if (data.size() > 4 && data.compare(data.size() - 4, 4, ".dat") == 0)
    return {Scan{knnocc::Point3f{}, knnocc::io::read_xyz(data).points}};
  return knnocc::bench::sequence_scans(data);
}

// One insertion of every scan on a fresh map and inserter; returns seconds, sets the map's counts.
// points_of(i): scan i's points as the version's Point3f.
template <class Map, class Inserter, class Point, class PointsOf>
double run(const std::vector<Scan>& scans, PointsOf points_of, double res, unsigned threads,
           std::size_t (&counts)[2]) {
  Map map(res);
  Inserter inserter(map, {}, threads);
  const double t0 = now();
  for (std::size_t i = 0; i < scans.size(); ++i) {
    const auto& o = scans[i].origin;
    inserter.insert_point_cloud(Point{o.x, o.y, o.z}, points_of(i));
  }
  const double t = now() - t0;
  const auto c = map.count_voxels();
  counts[0] = c.occupied;
  counts[1] = c.free;
  return t;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: ab_insert THREADS PAIRS RES DATA (run bench/ab_insert.sh)\n");
    return 2;
  }
  const auto threads = static_cast<unsigned>(std::max(1, std::atoi(argv[1])));
  const int pairs = std::max(1, std::atoi(argv[2]));
  const double res = std::atof(argv[3]);
  const auto scans = load(argv[4]);
  std::vector<std::vector<knnocc_old::Point3f>> old_points;  // the same points, the old type
  for (const auto& s : scans) {
    old_points.emplace_back();
    for (const auto& p : s.points) old_points.back().push_back({p.x, p.y, p.z});
  }
  const auto new_of = [&](std::size_t i) -> const auto& { return scans[i].points; };
  const auto old_of = [&](std::size_t i) -> const auto& { return old_points[i]; };
  std::vector<double> t_old, t_new;
  std::size_t c_old[2] = {0, 0}, c_new[2] = {0, 0};
  bool same = true;
  for (int pair = 0; pair < pairs; ++pair)
    for (int k = 0; k < 2; ++k) {
      if ((k == 0) == (pair % 2 == 0))  // the order alternates too
        t_old.push_back(run<knnocc_old::OccupancyMap<knnocc_old::OcKey>,
                            knnocc_old::ScanInserter<knnocc_old::OcKey>, knnocc_old::Point3f>(
            scans, old_of, res, threads, c_old));
      else
        t_new.push_back(
            run<knnocc::OccupancyMap<knnocc::OcKey>, knnocc::ScanInserter<knnocc::OcKey>,
                knnocc::Point3f>(scans, new_of, res, threads, c_new));
      if (t_old.size() == t_new.size()) same = same && c_old[0] == c_new[0] && c_old[1] == c_new[1];
    }
  std::vector<double> ratio;
  for (std::size_t i = 0; i < t_old.size(); ++i) ratio.push_back(t_new[i] / t_old[i]);
  std::sort(ratio.begin(), ratio.end());
  const double best_old = *std::min_element(t_old.begin(), t_old.end());
  const double best_new = *std::min_element(t_new.begin(), t_new.end());
  std::printf(
      "ab_insert: %s, res %g m, %u thread%s, %d pairs\n  old best %.4f s, new best %.4f s: "
      "new/old %.3f (bests), %.3f (median of the pairs)\n  same map: %s (occupied %zu, free "
      "%zu)\n",
      argv[4], res, threads, threads > 1 ? "s" : "", pairs, best_old, best_new, best_new / best_old,
      ratio[ratio.size() / 2], same ? "yes" : "NO, MAPS DIFFER", c_new[0], c_new[1]);
  return same ? 0 : 1;
}
