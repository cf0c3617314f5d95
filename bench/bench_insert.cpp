// bench_insert: OctoMap-model insertion of real scans with knnocc and, when found, liboctomap in
// the same run. Prints times, the speed-up, voxel updates per second and map memory, and checks
// that both libraries built the same map (counts of occupied and free finest-level voxels).
//
// usage: bench_insert [--res R]... [--repeat N] [--data DIR]
//   DIR defaults to ../shared/data (run from the project root). Uses
//   octomap_fr079/scan.dat.bz2 (decompressed into build/data/ on first use) and
//   tum_fr2_pioneer_slam2 (10 Kinect clouds). Resolutions default to 0.1 and 0.05.

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <knnocc/io/sequence.hpp>
#include <knnocc/io/xyz.hpp>
#include <knnocc/map/scan_inserter.hpp>
#include <knnocc/version.hpp>

#if KNNOCC_HAVE_OCTOMAP
#include <octomap/OcTree.h>
#endif

namespace fs = std::filesystem;
using knnocc::OcKey;
using knnocc::Point3f;

namespace {

struct Scan {
  Point3f origin;
  std::vector<Point3f> points;
};

struct Dataset {
  std::string name;
  std::vector<Scan> scans;
  std::size_t points() const {
    std::size_t n = 0;
    for (const auto& s : scans) n += s.points.size();
    return n;
  }
};

double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// scan.dat ships bz2-compressed; decompress once into build/data (as the test fixture does).
std::string scan_dat(const fs::path& data) {
  const fs::path bz2 = data / "octomap_fr079" / "scan.dat.bz2";
  const fs::path out = fs::path("build") / "data" / "scan.dat";
  if (fs::exists(out)) return out.string();
  if (!fs::exists(bz2)) return {};
  fs::create_directories(out.parent_path());
  const std::string tmp = out.string() + ".tmp";
  const std::string cmd = "bzip2 -dc '" + bz2.string() + "' > '" + tmp + "'";
  if (std::system(cmd.c_str()) != 0) return {};
  fs::rename(tmp, out);
  return out.string();
}

std::vector<Dataset> load(const fs::path& data) {
  std::vector<Dataset> sets;
  if (const std::string p = scan_dat(data); !p.empty()) {
    Dataset d{"fr079 scan.dat (1 scan)", {}};
    d.scans.push_back(Scan{Point3f{}, knnocc::io::read_xyz(p).points});
    sets.push_back(std::move(d));
  }
  if (fs::is_directory(data / "tum_fr2_pioneer_slam2")) {
    const auto seq = knnocc::io::Sequence::open((data / "tum_fr2_pioneer_slam2").string());
    Dataset d{"TUM fr2/pioneer_slam2 (10 clouds)", {}};
    for (std::size_t i = 0; i < seq.size(); ++i) {
      Scan s;
      knnocc::io::transform_to_world(seq.pose(i), seq.load_cloud(i).points, s.points);
      const auto& t = seq.pose(i).t;
      s.origin = Point3f{float(t.x()), float(t.y()), float(t.z())};
      d.scans.push_back(std::move(s));
    }
    sets.push_back(std::move(d));
  }
  return sets;
}

struct Result {
  double seconds = 0;
  std::size_t occupied = 0, free = 0, ray_keys = 0, updates = 0, bytes = 0;
};

Result run_knnocc(const Dataset& d, double res, int repeat) {
  Result best;
  best.seconds = 1e30;
  for (int r = 0; r < repeat; ++r) {
    knnocc::OccupancyMap<OcKey> map(res);
    knnocc::ScanInserter<OcKey> inserter(map);
    std::size_t keys = 0, updates = 0;
    const double t0 = now();
    for (const auto& s : d.scans) {
      const auto st = inserter.insert_point_cloud(s.origin, s.points);
      keys += st.ray_keys;
      updates += st.occupied_voxels + st.free_voxels;
    }
    const double t = now() - t0;
    if (t < best.seconds) {
      const auto c = map.count_voxels();
      best = Result{t, c.occupied, c.free, keys, updates, map.memory_usage()};
    }
  }
  return best;
}

#if KNNOCC_HAVE_OCTOMAP
Result run_octomap(const Dataset& d, double res) {
  octomap::OcTree tree(res);
  std::vector<octomap::Pointcloud> clouds(d.scans.size());
  for (std::size_t i = 0; i < d.scans.size(); ++i)
    for (const auto& p : d.scans[i].points) clouds[i].push_back(p.x, p.y, p.z);
  const double t0 = now();
  for (std::size_t i = 0; i < d.scans.size(); ++i) {
    const auto& o = d.scans[i].origin;
    tree.insertPointCloud(clouds[i], octomap::point3d(o.x, o.y, o.z));
  }
  Result r;
  r.seconds = now() - t0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const std::size_t span = std::size_t{1} << (16 - it.getDepth());
    (tree.isNodeOccupied(*it) ? r.occupied : r.free) += span * span * span;
  }
  r.bytes = tree.memoryUsage();
  return r;
}
#endif

}  // namespace

int main(int argc, char** argv) {
  std::vector<double> resolutions;
  int repeat = 3;
  fs::path data = fs::path("..") / "shared" / "data";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--res" && i + 1 < argc)
      resolutions.push_back(std::atof(argv[++i]));
    else if (a == "--repeat" && i + 1 < argc)
      repeat = std::max(1, std::atoi(argv[++i]));
    else if (a == "--data" && i + 1 < argc)
      data = argv[++i];
    else {
      std::fprintf(stderr, "usage: bench_insert [--res R]... [--repeat N] [--data DIR]\n");
      return 2;
    }
  }
  if (resolutions.empty()) resolutions = {0.1, 0.05};

  std::printf("bench_insert: knnocc %s, build type '%s', flags '%s', %s\n", knnocc::version_string,
              KNNOCC_BENCH_BUILD_TYPE, KNNOCC_BENCH_CXX_FLAGS,
#if KNNOCC_HAVE_OCTOMAP
              "liboctomap in the same run");
#else
              "liboctomap not found (knnocc only)");
#endif
  const auto sets = load(data);
  if (sets.empty()) {
    std::fprintf(stderr, "bench_insert: no datasets under %s (run from the project root)\n",
                 data.string().c_str());
    return 2;
  }
  std::printf("%-34s %5s %9s %10s %9s %9s %8s %11s %9s %9s\n", "dataset", "res", "points",
              "ray keys", "knnocc s", "octomap s", "speedup", "Mupdates/s", "knnocc MB",
              "octomap MB");
  for (const auto& d : sets) {
    for (const double res : resolutions) {
      const Result k = run_knnocc(d, res, repeat);
      double o_s = 0, o_mb = 0;
      bool same = true;
#if KNNOCC_HAVE_OCTOMAP
      const Result o = run_octomap(d, res);
      o_s = o.seconds;
      o_mb = o.bytes / 1e6;
      same = o.occupied == k.occupied && o.free == k.free;
#endif
      std::printf("%-34s %5.3g %9zu %10zu %9.3f %9.3f %7.1fx %11.1f %9.1f %9.1f%s\n",
                  d.name.c_str(), res, d.points(), k.ray_keys, k.seconds, o_s,
                  o_s > 0 ? o_s / k.seconds : 0.0, k.ray_keys / k.seconds / 1e6, k.bytes / 1e6,
                  o_mb, same ? "" : "  MAPS DIFFER");
      std::printf("%-34s       occupied %zu free %zu (finest-level voxels)\n", "", k.occupied,
                  k.free);
    }
  }
  struct rusage ru {};
  getrusage(RUSAGE_SELF, &ru);
  std::printf("peak RSS of this process: %.1f MB (both libraries together)\n",
              ru.ru_maxrss / 1024.0);
  return 0;
}
