#pragma once
// What the bench programs share: a monotonic clock in seconds, the resident memory, a run in a
// forked child measuring the peak memory it adds, the scan.dat dataset, and liboctomap's insertion
// as the baseline (KNNOCC_HAVE_OCTOMAP builds).

#include <malloc.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <knnocc/core/point3.hpp>
#include <knnocc/io/sequence.hpp>

#if KNNOCC_HAVE_OCTOMAP
#include <octomap/OcTree.h>
#endif

namespace knnocc::bench {

inline double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// scan.dat ships bz2-compressed; decompress once into build/data (as the test fixture does).
// Returns its path, or "" when the data folder or bzip2 is missing.
inline std::string scan_dat(const std::filesystem::path& data) {
  namespace fs = std::filesystem;
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

/// One scan: the sensor position and its points, in the world frame.
struct Scan {
  Point3f origin;
  std::vector<Point3f> points;
};

/// The clouds of a sequence directory (io::Sequence) in the world frame, each seen from its
/// pose's position.
inline std::vector<Scan> sequence_scans(const std::string& dir) {
  const auto seq = io::Sequence::open(dir);
  std::vector<Scan> scans(seq.size());
  for (std::size_t i = 0; i < seq.size(); ++i) {
    io::transform_to_world(seq.pose(i), seq.load_cloud(i).points, scans[i].points);
    const auto& t = seq.pose(i).t;
    scans[i].origin = Point3f{float(t.x()), float(t.y()), float(t.z())};
  }
  return scans;
}

/// Current resident memory of this process, in MB (0 when /proc is not there).
inline double resident_mb() {
  long pages = 0, resident = 0;
  if (FILE* f = std::fopen("/proc/self/statm", "r")) {
    if (std::fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = 0;
    std::fclose(f);
  }
  return static_cast<double>(resident) * (static_cast<double>(sysconf(_SC_PAGESIZE)) / 1024.0) /
         1024.0;
}

/// Resets this process's peak resident memory to its current resident memory (Linux:
/// /proc/self/clear_refs); false where that is not possible.
inline bool reset_peak_rss() {
  FILE* f = std::fopen("/proc/self/clear_refs", "w");
  if (!f) return false;
  const bool ok = std::fputs("5", f) >= 0;
  return std::fclose(f) == 0 && ok;
}

/// Peak resident memory of this process (VmHWM), in MB; 0 when /proc is not there.
inline double peak_rss_mb() {
  double kb = 0;
  if (FILE* f = std::fopen("/proc/self/status", "r")) {
    char line[256];
    while (std::fgets(line, sizeof line, f))
      if (std::sscanf(line, "VmHWM: %lf kB", &kb) == 1) break;
    std::fclose(f);
  }
  return kb / 1024.0;
}

/// Runs f() in a forked child; returns its result (trivially copyable: sent through a pipe) and
/// the peak RSS in MB it added to what the child had when it started (the datasets, inherited
/// from the caller). The child's peak is reset first: a forked child inherits the parent's peak,
/// which would hide a small insertion.
template <class F>
auto in_child(F f) -> std::pair<decltype(f()), double> {
  using Result = decltype(f());
  static_assert(std::is_trivially_copyable_v<Result>, "in_child sends the result through a pipe");
  struct Message {
    Result result;
    double added_mb;
  };
  int fd[2];
  if (pipe(fd) != 0) std::exit(2);
  const pid_t pid = fork();
  if (pid == 0) {
    Message m;
    malloc_trim(0);  // heap left free by earlier runs would hide the child's own allocations
    const bool reset = reset_peak_rss();
    const double start_mb = resident_mb();
    m.result = f();
    struct rusage ru {};
    getrusage(RUSAGE_SELF, &ru);
    // Without the reset (not Linux) the peak since the fork is all there is.
    const double peak_mb = reset ? peak_rss_mb() : ru.ru_maxrss / 1024.0;
    m.added_mb = peak_mb - start_mb;
    if (write(fd[1], &m, sizeof m) != static_cast<ssize_t>(sizeof m)) _exit(1);
    _exit(0);
  }
  close(fd[1]);
  Message m{};
  if (read(fd[0], &m, sizeof m) != static_cast<ssize_t>(sizeof m)) m = Message{};
  close(fd[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  return {m.result, m.added_mb};
}

/// A finished child process.
struct Child {
  double seconds = 0;
  double peak_mb = 0;
  int status = -1;
  std::string output;
};

/// Runs argv as a child process (its standard output captured, stderr passed through): wall time
/// from fork to exit, the child's peak RSS.
inline Child run_process(const std::vector<std::string>& args) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  int pipefd[2];
  if (pipe(pipefd) != 0) std::exit(2);
  Child c;
  const double t0 = now();
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(pipefd[1], 1);
    close(pipefd[0]);
    close(pipefd[1]);
    execv(argv[0], argv.data());
    _exit(127);
  }
  close(pipefd[1]);
  char buf[4096];
  for (ssize_t n; (n = read(pipefd[0], buf, sizeof buf)) > 0;) c.output.append(buf, std::size_t(n));
  close(pipefd[0]);
  struct rusage ru {};
  wait4(pid, &c.status, 0, &ru);
  c.seconds = now() - t0;
  c.peak_mb = ru.ru_maxrss / 1024.0;
  while (!c.output.empty() && c.output.back() == '\n') c.output.pop_back();
  return c;
}

#if KNNOCC_HAVE_OCTOMAP
inline octomap::Pointcloud octomap_cloud(const std::vector<Point3f>& points) {
  octomap::Pointcloud cloud;
  for (const auto& p : points) cloud.push_back(p.x, p.y, p.z);
  return cloud;
}

/// What liboctomap's run produced: the time of the insertions alone, finest-level voxel counts
/// (leaves expanded) and memoryUsage().
struct OctomapRun {
  double seconds = 0;
  std::size_t occupied = 0, free = 0, bytes = 0;
};

/// liboctomap's insertPointCloud of clouds[i] from origins[i] into a new tree (the clouds are
/// built before the clock starts).
inline OctomapRun run_octomap(const std::vector<octomap::Pointcloud>& clouds,
                              const std::vector<Point3f>& origins, double res,
                              double max_range = -1.0) {
  octomap::OcTree tree(res);
  OctomapRun r;
  const double t0 = now();
  for (std::size_t i = 0; i < clouds.size(); ++i)
    tree.insertPointCloud(clouds[i], octomap::point3d(origins[i].x, origins[i].y, origins[i].z),
                          max_range);
  r.seconds = now() - t0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const std::size_t span = std::size_t{1} << (16 - it.getDepth());
    (tree.isNodeOccupied(*it) ? r.occupied : r.free) += span * span * span;
  }
  r.bytes = tree.memoryUsage();
  return r;
}
#endif

}  // namespace knnocc::bench
