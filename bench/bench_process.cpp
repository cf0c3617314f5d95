// bench_process: the whole `knnocc map` process (start, read a binary PLY, insert, count, exit)
// against liboctomap's insertion alone, in the same run. Also the peak memory of both: the
// knnocc process's, and that of a forked child that inserts the same points with liboctomap.
//
// The input is fr079 scan.dat as a sequence folder with one binary PLY cloud (identity pose),
// written to build/data/scan_dat_seq/ on first use.
//
// usage: bench_process [--res R]... [--runs N] [--threads N] [--data DIR]   (run from the root)

#include <malloc.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "bench_common.hpp"

#include <knnocc/io/ply.hpp>
#include <knnocc/io/xyz.hpp>
#include <knnocc/version.hpp>

#if KNNOCC_HAVE_OCTOMAP
#include <octomap/OcTree.h>
#endif

namespace fs = std::filesystem;

namespace {

using knnocc::bench::Child;
using knnocc::bench::now;
using knnocc::bench::run_process;
using knnocc::bench::scan_dat;

#if KNNOCC_HAVE_OCTOMAP
// liboctomap's insertPointCloud alone (the point cloud is built before the clock starts).
double octomap_insert(const std::vector<knnocc::Point3f>& points, double res) {
  return knnocc::bench::run_octomap({knnocc::bench::octomap_cloud(points)}, {knnocc::Point3f{}},
                                    res)
      .seconds;
}

using knnocc::bench::resident_mb;

// The same in a forked child: its peak RSS, and the RSS it started with (this benchmark's, the
// points included, after returning free heap memory to the system).
std::pair<double, double> octomap_peak_mb(const std::vector<knnocc::Point3f>& points, double res) {
  int fd[2];
  if (pipe(fd) != 0) std::exit(2);
  const pid_t pid = fork();
  if (pid == 0) {
    malloc_trim(0);
    const double start = resident_mb();
    if (write(fd[1], &start, sizeof start) != static_cast<ssize_t>(sizeof start)) _exit(1);
    octomap_insert(points, res);
    _exit(0);
  }
  close(fd[1]);
  double start = 0;
  if (read(fd[0], &start, sizeof start) != static_cast<ssize_t>(sizeof start)) start = 0;
  close(fd[0]);
  int status = 0;
  struct rusage ru {};
  wait4(pid, &status, 0, &ru);
  return {ru.ru_maxrss / 1024.0, start};
}
#endif

}  // namespace

int main(int argc, char** argv) {
  std::vector<double> resolutions;
  int runs = 5;
  std::string threads = "1";
  fs::path data = fs::path("..") / "shared" / "data";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--res" && i + 1 < argc)
      resolutions.push_back(std::atof(argv[++i]));
    else if (a == "--runs" && i + 1 < argc)
      runs = std::max(1, std::atoi(argv[++i]));
    else if (a == "--threads" && i + 1 < argc)
      threads = argv[++i];
    else if (a == "--data" && i + 1 < argc)
      data = argv[++i];
    else {
      std::fprintf(stderr,
                   "usage: bench_process [--res R]... [--runs N] [--threads N] [--data DIR]\n");
      return 2;
    }
  }
  if (resolutions.empty()) resolutions = {0.1, 0.05};
  const std::string tool = KNNOCC_TOOL_PATH;
  std::printf("bench_process: knnocc %s, build type '%s', tool %s, %s\n", knnocc::version_string,
              KNNOCC_BENCH_BUILD_TYPE, tool.c_str(),
#if KNNOCC_HAVE_OCTOMAP
              "liboctomap in the same run");
#else
              "liboctomap not found (knnocc only)");
#endif
  const std::string dat = scan_dat(data);
  if (dat.empty()) {
    std::fprintf(stderr, "bench_process: no scan.dat under %s (run from the project root)\n",
                 data.string().c_str());
    return 2;
  }
  const auto points = knnocc::io::read_xyz(dat).points;
  const fs::path seq = fs::path("build") / "data" / "scan_dat_seq";
  if (!fs::exists(seq / "clouds" / "000000.ply")) {
    fs::create_directories(seq / "clouds");
    knnocc::io::write_ply((seq / "clouds" / "000000.ply").string(), points);  // binary LE
    std::ofstream(seq / "poses.txt") << "0 0 0 0 0 0 0 1\n";
  }
  std::printf("input: %s (binary PLY, %zu points, sensor at the origin)\n", seq.string().c_str(),
              points.size());

  for (const double res : resolutions) {
    const std::vector<std::string> cmd = {tool,        "map",     "--input", seq.string(),
                                          "--model",   "octomap", "--res",   std::to_string(res),
                                          "--threads", threads};
    Child best;
    best.seconds = 1e30;
    for (int r = 0; r < runs; ++r) {
      const Child c = run_process(cmd);
      if (c.status != 0) {
        std::fprintf(stderr, "bench_process: %s failed (status %d)\n", tool.c_str(), c.status);
        return 2;
      }
      if (c.seconds < best.seconds) best = c;
    }
    std::printf("\nres %g: knnocc map --input %s --model octomap --res %g --threads %s\n", res,
                seq.string().c_str(), res, threads.c_str());
    std::printf("  tool says: %s\n", best.output.c_str());
    std::printf("  whole process: %.4f s (best of %d), peak RSS %.1f MB\n", best.seconds, runs,
                best.peak_mb);
#if KNNOCC_HAVE_OCTOMAP
    const double o = octomap_insert(points, res);
    const auto [peak, base] = octomap_peak_mb(points, res);
    std::printf(
        "  liboctomap insertPointCloud alone: %.4f s; peak RSS %.1f MB of a process that "
        "holds the points and inserts them (%.1f MB before inserting)\n",
        o, peak, base);
    std::printf(
        "  => whole knnocc process %.1fx faster than liboctomap's insertion alone; peak "
        "RSS %.2f of liboctomap's\n",
        o / best.seconds, best.peak_mb / peak);
#endif
  }
  return 0;
}
