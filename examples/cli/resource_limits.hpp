#pragma once
// What the machine allows a command: threads (capped at the hardware threads) and memory
// (--memory-limit): the limit is the process's address-space limit, so an allocation past it
// fails as std::bad_alloc (reported in one line, exit 2) instead of the kernel killing the
// process; the map gets its share as OccupancyMap's memory limit; work that surely cannot fit is
// refused before it starts (at_least_bricks(), at_least_bricks_by_angle()).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include <knnocc/core/detail/flat_index.hpp>
#include <knnocc/core/point3.hpp>
#include <knnocc/io/octomap_tree.hpp>
#include <knnocc/map/brick.hpp>
#include <knnocc/map/occupancy_map.hpp>

#include "args.hpp"

#if defined(__unix__) || defined(__APPLE__)
#include <sys/resource.h>
#include <unistd.h>
#define KNNOCC_CLI_RLIMIT 1
#else
#define KNNOCC_CLI_RLIMIT 0
#endif

// An address-space limit would break the sanitizers' shadow memory.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define KNNOCC_CLI_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || \
    __has_feature(memory_sanitizer)
#define KNNOCC_CLI_SANITIZED 1
#endif
#endif
#ifndef KNNOCC_CLI_SANITIZED
#define KNNOCC_CLI_SANITIZED 0
#endif

namespace knnocc::cli {

/// A --threads request above the machine's hardware threads is capped there, with a note on
/// stderr: more threads would only wait for a core (the map is the same for every count).
inline unsigned cap_threads(const char* command, long requested) {
  const unsigned hw = std::thread::hardware_concurrency();
  if (hw == 0 || requested <= static_cast<long>(hw)) return static_cast<unsigned>(requested);
  std::fprintf(stderr,
               "knnocc %s: --threads %ld is more than the %u hardware threads of this machine; "
               "using %u\n",
               command, requested, hw, hw);
  return hw;
}

/// "1.5 GB" style (decimal units).
inline std::string format_bytes(double bytes) {
  char s[32];
  if (bytes >= 1e9)
    std::snprintf(s, sizeof s, "%.1f GB", bytes / 1e9);
  else
    std::snprintf(s, sizeof s, "%.0f MB", bytes / 1e6);
  return s;
}

/// What map says when an allocation fails under --memory-limit: "out of memory (--memory-limit
/// 1.0 GB) <doing> at --res 0.1; a higher --memory-limit, or a coarser --res or --crop".
inline std::string out_of_memory_text(double limit, const char* doing, double res) {
  char res_text[32];
  std::snprintf(res_text, sizeof res_text, "%g", res);
  return "out of memory (--memory-limit " + format_bytes(limit) + ") " + doing + " at --res " +
         res_text + "; a higher --memory-limit, or a coarser --res or --crop";
}

/// The memory this machine gives the process: physical memory, lowered by an address-space
/// limit and a cgroup (container) limit where set.
inline double machine_memory() {
  double bytes = 0;
#if KNNOCC_CLI_RLIMIT
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
  if (pages > 0 && page > 0) bytes = double(pages) * double(page);
  rlimit rl{};
  if (::getrlimit(RLIMIT_AS, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY)
    bytes = bytes > 0 ? std::min(bytes, double(rl.rlim_cur)) : double(rl.rlim_cur);
  for (const char* cg :
       {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"}) {
    if (std::FILE* f = std::fopen(cg, "r")) {
      double v = 0;
      if (std::fscanf(f, "%lf", &v) == 1 && v > 0) bytes = bytes > 0 ? std::min(bytes, v) : v;
      std::fclose(f);
    }
  }
#endif
  return bytes > 0 ? bytes : 4e9;
}

/// The default --memory-limit: 80 % of machine_memory().
inline double default_memory_limit() { return 0.8 * machine_memory(); }

/// The current limit (bytes), for messages.
inline double& memory_limit_bytes() {
  static double bytes = 0;
  return bytes;
}

/// Makes `bytes` the process's address-space limit (never above the hard limit), so allocations
/// past it fail as std::bad_alloc. Skipped in sanitizer builds.
inline void apply_memory_limit(double bytes) {
  memory_limit_bytes() = bytes;
#if KNNOCC_CLI_RLIMIT && !KNNOCC_CLI_SANITIZED
  rlimit rl{};
  if (::getrlimit(RLIMIT_AS, &rl) != 0) return;
  rlim_t want = bytes >= 1.8e19 ? RLIM_INFINITY : static_cast<rlim_t>(bytes);
  if (rl.rlim_max != RLIM_INFINITY && want > rl.rlim_max) want = rl.rlim_max;
  rl.rlim_cur = want;
  (void)::setrlimit(RLIMIT_AS, &rl);
#endif
}

/// The map's share of the memory limit (the rest holds clouds, rays and the k-NN tracker).
inline std::size_t map_memory_share(double limit) { return static_cast<std::size_t>(0.75 * limit); }

/// How the tool reads .bt/.ot maps: bounded by the map's share of the memory limit.
inline io::OctreeReadOptions tree_read_options() {
  io::OctreeReadOptions o;
  o.memory_limit = map_memory_share(memory_limit_bytes());
  return o;
}

/// The finest resolution the tool maps at (map --res): 16-bit keys then span +-3.3 m.
inline constexpr double kMinResolution = 1e-4;

/// A map file finer than kMinResolution is refused by every command alike.
inline void check_tree_resolution(const std::string& path, double res) {
  if (res < kMinResolution) {
    char s[128];
    std::snprintf(s, sizeof s, "resolution %g is below %g, the finest the tool maps at", res,
                  kMinResolution);
    throw io::Error(path, s);
  }
}

/// The least memory one brick of a map takes: its record and its index slots (a brick that one
/// update made uniform has no value array).
inline constexpr std::size_t kBrickBytesAtLeast =
    sizeof(OccupancyMap<OcKey>::Brick) + 2 * (sizeof(std::uint64_t) + sizeof(std::uint32_t));

/// f(), the work on `path` that `doing` names ("reading it"); running out of memory in it
/// becomes one io::Error naming the file and --memory-limit.
template <class F>
auto within_memory(const std::string& path, const char* doing, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const std::bad_alloc&) {  // MemoryLimitError included
    throw io::Error(path, "out of memory (--memory-limit " + format_bytes(memory_limit_bytes()) +
                              ") " + doing + "; a higher --memory-limit may let it fit");
  }
}

/// read() (which reads `path`); running out of memory in it becomes one io::Error naming the
/// file and --memory-limit.
template <class Read>
auto reading(const std::string& path, Read&& read) -> decltype(read()) {
  try {
    return read();
  } catch (const std::bad_alloc&) {  // MemoryLimitError included
    throw io::Error(path, "out of memory (--memory-limit " + format_bytes(memory_limit_bytes()) +
                              ") reading it; a higher --memory-limit reads it");
  }
}

/// A .bt/.ot map as the tool reads it: resolution checked, memory bounded by the map's share of
/// --memory-limit; a tree too large for it, or running out while reading it, is one io::Error
/// naming the file and --memory-limit. With `colors`, a ColorOcTree's colours go there.
inline OccupancyMap<OcKey> read_tree_checked(const std::string& path,
                                             const OccupancyParams& params = {},
                                             io::OctreeColors* colors = nullptr) {
  const io::OctreeInfo info = io::inspect_octree(path);
  check_tree_resolution(path, info.resolution);
  const double limit = memory_limit_bytes(), share = double(map_memory_share(limit));
  const double bricks = std::ceil(double(info.occupied_voxels + info.free_voxels) / kBrickVoxels);
  if (share > 0 && bricks * double(kBrickBytesAtLeast) > share)
    throw io::Error(path, "the tree's " + std::to_string(info.occupied_voxels + info.free_voxels) +
                              " voxels need at least " + format_bytes(bricks * kBrickBytesAtLeast) +
                              " as a map, more than the map's share (" + format_bytes(share) +
                              ") of --memory-limit " + format_bytes(limit) +
                              "; a higher --memory-limit reads it");
  io::OctreeReadOptions options = tree_read_options();
  options.params = params;  // the clamping of the map it becomes (--clamp)
  return reading(path, [&] {
    return colors ? io::read_octree_colors(path, options, *colors) : io::read_octree(path, options);
  });
}

/// The part of each ray from `origin` that a scan stores, as the map sees it: endpoints beyond
/// the key range (32768 voxels from the centre) are skipped, rays are cut at max_range (> 0).
struct StoredRays {
  Point3d origin;
  double reach, max_range;
  StoredRays(const Point3d& o, double res, double cut)
      : origin(o), reach(32768.0 * res), max_range(cut) {}
  bool in_range(double x, double y, double z) const {
    return std::fabs(x) < reach && std::fabs(y) < reach && std::fabs(z) < reach;
  }
  /// Length of the stored part of the ray to p (-1 for a skipped point); `full`: the whole ray.
  template <class P>
  double length(const P& p, double& full) const {
    const double dx = double(p.x) - origin.x, dy = double(p.y) - origin.y,
                 dz = double(p.z) - origin.z;
    full = std::sqrt(dx * dx + dy * dy + dz * dz);
    if (!std::isfinite(full) || !in_range(p.x, p.y, p.z)) return -1.0;
    return max_range > 0 ? std::min(full, max_range) : full;
  }
};

/// A lower bound on the bricks the rays of one scan (from `origin`, cut at max_range when > 0)
/// pass through, from their directions and lengths alone, in one pass over the points per angle:
///   - of two rays at least theta apart, a point at range r on one is at least r sin(theta) from
///     the other, and two points in one brick are at most sqrt(3) * edge apart, so beyond
///     r0 = sqrt(3) * edge / sin(theta) no brick holds both rays;
///   - a part of length l of a ray crosses at least l / (sqrt(3) * edge) bricks.
/// Rays pairwise at least theta apart are picked greedily (directions hashed into cells of one
/// chord), for theta from 0.1 rad halving down to where r0 passes every ray, and the largest sum
/// of their bricks beyond r0 is returned (less one brick per ray: a ray cut at max_range does not
/// free its last voxel). It proves the need of the long, many rays of a fine resolution without
/// walking them, where sampling (at_least_bricks) has to stop.
template <class P>
double at_least_bricks_by_angle(const Point3d& origin, const std::vector<P>& pts, double res,
                                double max_range) {
  const double edge = res * kBrickEdge, chord = std::sqrt(3.0) * edge;
  const StoredRays stored(origin, res, max_range);
  if (!stored.in_range(origin.x, origin.y, origin.z)) return 0;
  struct Ray {
    double x, y, z, l;  // unit direction, stored length
  };
  std::vector<Ray> rays;
  rays.reserve(pts.size());
  double longest = 0, full = 0;
  for (const P& p : pts) {
    const double l = stored.length(p, full);
    if (l < 0 || full == 0) continue;
    rays.push_back({(double(p.x) - origin.x) / full, (double(p.y) - origin.y) / full,
                    (double(p.z) - origin.z) / full, l});
    longest = std::max(longest, l);
  }
  double best = 0;
  std::vector<const Ray*> picked;
  std::vector<std::uint32_t> last, next;  // per cell 1 + its last picked ray, then 1 + the one
                                          // before it (0: none)
  for (double theta = 0.1; theta > 1e-7; theta /= 2) {
    const double r0 = chord / std::sin(theta);
    if (r0 >= longest) break;
    const double cell = 2 * std::sin(theta / 2);  // the chord between directions theta apart
    const double offset = std::floor(1 / cell) + 2;
    auto cell_of = [&](double c) {
      return static_cast<std::uint64_t>(std::floor(c / cell) + offset);
    };
    knnocc::detail::FlatIndex cells;  // cell -> its slot in `last`
    last.clear();
    next.clear();
    picked.clear();
    double sum = 0;
    for (const Ray& r : rays) {
      if (r.l - r0 < 2 * chord) continue;  // adds nothing beyond r0
      const std::uint64_t cx = cell_of(r.x), cy = cell_of(r.y), cz = cell_of(r.z);
      bool apart = true;
      for (std::uint64_t x = cx - 1; x <= cx + 1 && apart; ++x)
        for (std::uint64_t y = cy - 1; y <= cy + 1 && apart; ++y)
          for (std::uint64_t z = cz - 1; z <= cz + 1 && apart; ++z) {
            const std::uint32_t slot = cells.find((x << 42) | (y << 21) | z);
            if (slot == knnocc::detail::FlatIndex::kNone) continue;
            for (std::uint32_t j = last[slot]; j != 0 && apart; j = next[j - 1]) {
              const Ray& q = *picked[j - 1];
              const double ex = q.x - r.x, ey = q.y - r.y, ez = q.z - r.z;
              apart = ex * ex + ey * ey + ez * ez >= cell * cell;
            }
          }
      if (!apart) continue;
      bool inserted = false;
      const std::uint32_t slot = cells.find_or_insert(
          (cx << 42) | (cy << 21) | cz, static_cast<std::uint32_t>(last.size()), inserted);
      if (inserted) last.push_back(0);
      picked.push_back(&r);
      next.push_back(last[slot]);
      last[slot] = static_cast<std::uint32_t>(picked.size());
      sum += std::floor((r.l - r0) / chord) - 1;
    }
    best = std::max(best, sum);
    if (picked.size() == rays.size()) break;  // every ray picked: a smaller angle only loses
  }
  return best;
}

/// A lower bound on the bricks one scan creates: the distinct bricks holding points sampled
/// along its rays (from `origin`, one sample per brick edge, rays cut at max_range when > 0;
/// endpoints only when `rays` is false), each of which a ray passes through. Stops counting past
/// `enough`. When sampling every ray would take more samples than 3 x `enough` (at most 4 M), a
/// subset of the rays is sampled (still a lower bound), after at_least_bricks_by_angle() had its
/// say (it returns enough + 1 when the directions prove more); when the samples cannot reach
/// `enough` it returns 0 at once.
template <class P>
std::size_t at_least_bricks(const Point3d& origin, const std::vector<P>& pts, double res,
                            double max_range, bool rays, std::size_t enough) {
  const double edge = res * kBrickEdge;
  const StoredRays stored(origin, res, max_range);
  if (!stored.in_range(origin.x, origin.y, origin.z)) return 0;
  double samples = 0, full = 0;
  for (const P& p : pts) {
    const double l = stored.length(p, full);
    if (l >= 0) samples += rays ? 2 + std::floor(l / edge) : 1;
  }
  if (samples <= double(enough)) return 0;  // cannot reach `enough`: nothing to refuse
  // Proving more than `enough` bricks takes more than `enough` samples: sample up to three times
  // that, and at most 4 M (the set of seen bricks then stays below ~100 MB).
  const double kMaxSamples = std::min(3.0 * double(enough) + 1e6, 4e6);
  if (rays && samples > kMaxSamples) {  // too many to walk: what the directions prove first
    const double by_angle = at_least_bricks_by_angle(origin, pts, res, max_range);
    if (by_angle > double(enough)) return enough + 1;
  }
  const std::size_t stride =
      samples > kMaxSamples ? static_cast<std::size_t>(std::ceil(samples / kMaxSamples)) : 1;
  knnocc::detail::FlatIndex seen;
  auto add = [&](double x, double y, double z) {
    const auto b = [&](double c) {
      return static_cast<std::uint64_t>(std::floor(c / edge) + 1048576.0) & 0x1fffff;
    };
    bool inserted = false;
    seen.find_or_insert((b(x) << 42) | (b(y) << 21) | b(z), 0, inserted);
  };
  for (std::size_t i = 0; i < pts.size() && seen.size() <= enough; i += stride) {
    const P& p = pts[i];
    const double l = stored.length(p, full);
    if (l < 0) continue;
    if (!rays || full == 0) {
      add(p.x, p.y, p.z);
      continue;
    }
    const double ux = (double(p.x) - origin.x) / full, uy = (double(p.y) - origin.y) / full,
                 uz = (double(p.z) - origin.z) / full;
    for (double t = 0; t < l && seen.size() <= enough; t += edge)
      add(origin.x + ux * t, origin.y + uy * t, origin.z + uz * t);
    if (l == full) add(p.x, p.y, p.z);
  }
  return seen.size();
}

}  // namespace knnocc::cli
