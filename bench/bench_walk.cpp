// bench_walk: what the insertion's two low-level costs are on this machine.
//   1. The ray walks into a dense scratch, per voxel visited, with bit marks and with byte marks:
//      scalar, four AVX2 lanes, two groups of eight AVX-512 lanes over a ray stream, and AVX-512
//      bundles of sixteen rays over RayBlocks (byte marks only; those the CPU has), on rays from
//      one origin to random points of a sphere shell (lengths 0.5-1 x R at 0.05 m; R = 4.8 m
//      gives ~108 voxels per ray, an L2-sized box in bits), in random order; and on the rays of a
//      depth camera in a room, in image order, as a scan's points come (the bundles' case:
//      neighbouring rays of nearly equal length).
//   2. A fresh page: the cost per 4 KB of first touching 64 MB of new anonymous memory, with 4 KB
//      pages and with MADV_HUGEPAGE (Linux; what detail/huge_pages.hpp relies on).
//
// usage: bench_walk [--length R]... [--rays N]

#include <sys/mman.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "bench_common.hpp"

#include <knnocc/raycast/detail/fan_walk.hpp>
#include <knnocc/raycast/detail/scan_bitmap.hpp>

namespace {

using namespace knnocc;

// camera: the rays of a depth camera (58 x 45 degrees) looking along +x in a room whose walls lie
// `length` away along x and y and length / 2 along z, in image order (neighbouring rays next to
// each other, as a scan's points come); else rays to random points of a sphere shell, in random
// order.
void walks(double length, int n_rays, bool camera) {
  const Grid<OcKey> grid(0.05);
  const Point3f o{0.01f, 0.02f, 0.03f};
  OcKey ko;
  grid.point_to_key(o, ko);
  const std::int32_t okey[3] = {ko[0], ko[1], ko[2]};
  std::int64_t lo[3], size[3];
  for (int a = 0; a < 3; ++a) {
    const auto r = static_cast<std::int64_t>(length / 0.05) + 16;
    lo[a] = (ko[a] - r) / 8 * 8;
    size[a] = (2 * r + 64) / 64 * 64;
  }
  detail::ScanBitmap bitmap, bytemap;
  bitmap.reshape(lo, size);
  bytemap.reshape(lo, size, true);
  const std::int64_t stride[3] = {1, size[0], size[0] * size[1]};
  const detail::RayFan fan(grid, o, okey, lo, stride);
  std::mt19937 rng(1);
  std::normal_distribution<float> n(0, 1);
  std::uniform_real_distribution<float> u(0.5f, 1.0f);
  std::vector<detail::RayEnd> rays;
  const int cols = static_cast<int>(std::sqrt(n_rays * 4.0 / 3.0)), rows = n_rays / cols;
  for (int v = 0; camera && v < rows; ++v)
    for (int c = 0; c < cols; ++c) {
      const double d[3] = {1.0, std::tan((c / (cols - 1.0) - 0.5) * 1.0123),
                           std::tan((v / (rows - 1.0) - 0.5) * 0.7854)};
      const double wall[3] = {length, length, 0.5 * length}, p[3] = {o.x, o.y, o.z};
      double t = 1e30;
      for (int a = 0; a < 3; ++a)
        if (d[a] != 0.0) t = std::min(t, ((d[a] > 0 ? wall[a] : -wall[a]) - p[a]) / d[a]);
      detail::RayEnd r;
      r.end = {static_cast<float>(p[0] + d[0] * t), static_cast<float>(p[1] + d[1] * t),
               static_cast<float>(p[2] + d[2] * t)};
      OcKey k;
      if (!grid.point_to_key(r.end, k) || k == ko) continue;
      for (int a = 0; a < 3; ++a) r.key[a] = k[a];
      rays.push_back(r);
    }
  while (!camera && static_cast<int>(rays.size()) < n_rays) {
    const float x = n(rng), y = n(rng), z = n(rng);
    const float s = static_cast<float>(length) * u(rng) / std::sqrt(x * x + y * y + z * z);
    detail::RayEnd r;
    r.end = {o.x + x * s, o.y + y * s, o.z + z * s};
    OcKey k;
    if (!grid.point_to_key(r.end, k) || k == ko) continue;
    for (int a = 0; a < 3; ++a) r.key[a] = k[a];
    rays.push_back(r);
  }
  std::vector<detail::LinearRay> linear(rays.size());
  detail::setup_linear_rays(grid, fan, rays.data(), rays.size(), linear.data());
  std::vector<std::unique_ptr<detail::RayBlock>> blocks;
  for (std::size_t first = 0; first < rays.size(); first += detail::RayBlock::kRays) {
    blocks.push_back(std::make_unique<detail::RayBlock>());
    detail::setup_ray_block(grid, fan, rays.data() + first,
                            std::min(detail::RayBlock::kRays, rays.size() - first), *blocks.back());
  }
  if (camera)
    std::printf(
        "\na depth camera's rays in a room %.1f m away at 0.05 m (%zu rays, box %.1f MB "
        "in bits):\n",
        length, rays.size(), double(size[0]) * size[1] * size[2] / 8e6);
  else
    std::printf(
        "\nrays of %.1f-%.1f m at 0.05 m in random order (%zu rays, box %.1f MB in "
        "bits):\n",
        0.5 * length, length, rays.size(), double(size[0]) * size[1] * size[2] / 8e6);
  const detail::BitMarks bits{bitmap.words()};
  const detail::ByteMarks bytes{bytemap.bytes()};
  using detail::WalkPath;
  for (int variant = 0; variant < 7; ++variant) {
    const bool byte_marks = variant >= 3;
    const int walk = byte_marks ? variant - 3 : variant;  // 0 scalar, 1 AVX2, 2 AVX-512, 3 bundles
    static const WalkPath paths[] = {WalkPath::scalar, WalkPath::avx2_lanes,
                                     WalkPath::avx512_stream, WalkPath::avx512_bundles};
    static const char* const names[] = {"scalar", "AVX2, 4 lanes", "AVX-512, 2x8 lanes",
                                        "AVX-512 bundles"};
    const WalkPath path = paths[walk];
    char name[64];
    std::snprintf(name, sizeof name, "%s, %s", names[walk], byte_marks ? "bytes" : "bits");
    if (!detail::walk_path_available(path)) {
      std::printf("  %-28s not available on this CPU\n", name);
      continue;
    }
    double best = 1e30;
    std::size_t visits = 0;
    for (int rep = 0; rep < 5; ++rep) {
      std::size_t i = 0;
      auto next = [&]() -> const detail::LinearRay* {
        return i == linear.size() ? nullptr : &linear[i++];
      };
      const double t0 = bench::now();
      if (path == WalkPath::avx512_bundles) {
        visits = 0;
        for (const auto& b : blocks) visits += detail::walk_ray_block(path, *b, bytes);
      } else {
        visits = byte_marks ? detail::walk_linear_rays(path, next, bytes)
                            : detail::walk_linear_rays(path, next, bits);
      }
      best = std::min(best, bench::now() - t0);
    }
    std::printf("  %-28s %.3f ns per voxel visited (%.1f visits per ray, best of 5)\n", name,
                best * 1e9 / static_cast<double>(visits),
                static_cast<double>(visits) / static_cast<double>(linear.size()));
  }
}

void fresh_pages() {
  std::printf("\nfirst touch of 64 MB of fresh memory (best of 4):\n");
  for (const bool huge : {false, true}) {
    double best = 1e30;
    const std::size_t bytes = std::size_t{64} << 20;
    for (int rep = 0; rep < 4; ++rep) {
      void* p = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
      if (p == MAP_FAILED) return;
#if defined(MADV_HUGEPAGE)
      if (huge) madvise(p, bytes, MADV_HUGEPAGE);
#endif
      auto* c = static_cast<volatile char*>(p);
      const double t0 = bench::now();
      for (std::size_t i = 0; i < bytes; i += 4096) c[i] = 1;
      best = std::min(best, bench::now() - t0);
      munmap(p, bytes);
    }
    std::printf("  %-22s %.2f us per 4 KB\n", huge ? "MADV_HUGEPAGE (2 MB)" : "4 KB pages",
                best * 1e6 / (bytes / 4096));
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<double> lengths;
  int n_rays = 200000;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--length" && i + 1 < argc)
      lengths.push_back(std::atof(argv[++i]));
    else if (a == "--rays" && i + 1 < argc)
      n_rays = std::max(1, std::atoi(argv[++i]));
    else {
      std::fprintf(stderr, "usage: bench_walk [--length R]... [--rays N]\n");
      return 2;
    }
  }
  if (lengths.empty()) lengths = {4.8, 2.0};
  std::printf("bench_walk: build type '%s'\n", KNNOCC_BENCH_BUILD_TYPE);
  for (const bool camera : {true, false})
    for (const double l : lengths) walks(l, n_rays, camera);
  fresh_pages();
  return 0;
}
