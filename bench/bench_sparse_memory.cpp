// bench_sparse_memory: memory per known voxel for sparse long rays (points spread over +-R
// around the sensor), knnocc's brick storage against liboctomap's octree on the same scan.
//   bench_sparse_memory [points=2000] [range_m=4000] [res=1] [octomap=1]
// Prints known voxels, bytes and bytes per known voxel for both, and the ratio; for knnocc also
// the insertion time and the process's peak resident memory. knnocc's figure is
// OccupancyMap::memory_usage(); OctoMap's is OcTree::memoryUsage() (its own estimate of nodes and
// child-pointer arrays). octomap=0 skips liboctomap (the 20,000-point probe: about 118 M
// known voxels, some 11 GB for liboctomap at the 95 bytes per known voxel it takes at 200 points,
// bench/NOTES.md). Bonxai: bench_bonxai_memory (built with -DKNNOCC_BONXAI_DIR).

#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include <knnocc/insertion/scan_inserter.hpp>
#include <knnocc/map/occupancy_map.hpp>

#include "bench_common.hpp"

#ifdef KNNOCC_HAVE_OCTOMAP
#include <octomap/OcTree.h>
#endif

int main(int argc, char** argv) {
  const std::size_t n = argc > 1 ? std::strtoul(argv[1], nullptr, 10) : 2000;
  const double range = argc > 2 ? std::atof(argv[2]) : 4000.0;
  const double res = argc > 3 ? std::atof(argv[3]) : 1.0;
  const bool with_octomap = argc > 4 ? std::atoi(argv[4]) != 0 : true;
  std::printf("bench_sparse_memory (%s build): %zu points uniform in +-%g m, res %g m\n",
              KNNOCC_BENCH_BUILD_TYPE, n, range, res);
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<float> u(static_cast<float>(-range), static_cast<float>(range));
  std::vector<knnocc::Point3f> pts(n);
  for (auto& p : pts) p = {u(rng), u(rng), u(rng)};

  knnocc::OccupancyMap<knnocc::OcKey> map(res);
  const double t0 = knnocc::bench::now();
  knnocc::insert_point_cloud(map, knnocc::Point3f{0, 0, 0}, pts);
  const double seconds = knnocc::bench::now() - t0;
  const double ours = static_cast<double>(map.memory_usage());
  const double known = static_cast<double>(map.num_voxels());
  std::printf("knnocc   known %12.0f voxels  bricks %10zu  %10.1f MB  %7.1f bytes/known voxel\n",
              known, map.num_bricks(), ours / 1e6, ours / known);
  // The process's peak so far: the map and the insertion's scratch (and the points).
  std::printf("knnocc   insertion %.2f s, process peak RSS %.1f MB\n", seconds,
              knnocc::bench::peak_rss_mb());
  map.compact();
  const double compacted = static_cast<double>(map.memory_usage());
  std::printf(
      "knnocc   after compact()                                 %10.1f MB  %7.1f bytes/known "
      "voxel\n",
      compacted / 1e6, compacted / known);
#ifdef KNNOCC_HAVE_OCTOMAP
  if (!with_octomap) {
    std::printf("octomap: skipped (octomap=0)\n");
    return 0;
  }
  octomap::OcTree tree(res);
  octomap::Pointcloud cloud;
  for (const auto& p : pts) cloud.push_back(p.x, p.y, p.z);
  tree.insertPointCloud(cloud, octomap::point3d(0, 0, 0));
  const double theirs = static_cast<double>(tree.memoryUsage());
  std::size_t leaves = 0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it)
    leaves += std::size_t{1} << (3 * (tree.getTreeDepth() - it.getDepth()));
  std::printf("octomap  known %12zu voxels  nodes  %10zu  %10.1f MB  %7.1f bytes/known voxel\n",
              leaves, tree.size(), theirs / 1e6, theirs / static_cast<double>(leaves));
  std::printf("knnocc / octomap memory: %.2f (after compact(): %.2f)\n", ours / theirs,
              compacted / theirs);
#else
  (void)with_octomap;
  std::printf("octomap: not found at configure time, not measured\n");
#endif
  return 0;
}
