// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The dense walks behind one dispatcher. A scan's rays share their origin (a RayFan); they are set
// up a RayBlock at a time and walked on a WalkPath: scalar, four AVX2 lanes, or the two AVX-512
// walks. Every path marks exactly walk_ray()'s voxels (tests walk each path against the scalar
// walk), so the path is a matter of speed only: best_walk_path() picks the fastest one this CPU
// runs, and callers (tests, benchmarks) may name one explicitly.

#include <algorithm>
#include <cstddef>
#include <memory>
#include <type_traits>

#include "../../core/config.hpp"
#include "../../core/detail/simd_support.hpp"
#include "linear_ray.hpp"
#include "ray_block.hpp"
#include "walk_avx2.hpp"
#include "walk_avx512.hpp"

namespace knnocc::detail {

/// Which code walks the rays.
enum class WalkPath {
  scalar,          ///< one ray at a time (every CPU)
  avx2_lanes,      ///< four rays at once over a ray stream (AVX2 and BMI2)
  avx512_stream,   ///< two groups of eight lanes over a ray stream (AVX-512F)
  avx512_bundles,  ///< blocks sixteen neighbouring rays at a time (AVX-512F); a ray stream that
                   ///< is not a block goes on avx512_stream
};

/// Whether this build has the path and this CPU runs it.
inline bool walk_path_available(WalkPath path) {
  switch (path) {
    case WalkPath::scalar:
      return true;
#if KNNOCC_AVX2_LANES
    case WalkPath::avx2_lanes:
      return cpu_has_avx2();
    case WalkPath::avx512_stream:
    case WalkPath::avx512_bundles:
      return cpu_has_avx512();
#else
    default:
      return false;
#endif
  }
  return false;
}

/// The fastest path this CPU runs for marks of type Marks: on AVX-512 CPUs bundles for byte marks
/// (a byte is marked by a plain store, and sixteen rays in lockstep then do not wait on each
/// other) and the eight-lane stream for bit marks (lanes at different points of their rays mark
/// different words); four lanes on AVX2 CPUs; else the scalar walk. KNNOCC_NO_AVX512 keeps AVX-512
/// CPUs on the AVX2 lanes.
template <class Marks>
WalkPath best_walk_path() {
#if !defined(KNNOCC_NO_AVX512)
  if (walk_path_available(WalkPath::avx512_stream))
    return std::is_same_v<Marks, ByteMarks> ? WalkPath::avx512_bundles : WalkPath::avx512_stream;
#endif
  if (walk_path_available(WalkPath::avx2_lanes)) return WalkPath::avx2_lanes;
  return WalkPath::scalar;
}

/// Walks every ray next() yields on `path` (which must be available), marking each voxel visited
/// (origin included, end excluded: exactly walk_ray()'s voxels). Returns the voxels visited.
template <class Next, class Marks>
std::size_t walk_linear_rays(WalkPath path, Next& next, Marks marks) {
#if KNNOCC_AVX2_LANES
  if (path == WalkPath::avx512_stream || path == WalkPath::avx512_bundles)
    return avx512_stream::walk(next, marks);
  if (path == WalkPath::avx2_lanes) return walk_linear_rays_avx2(next, marks);
#endif
  (void)path;
  return walk_linear_rays_scalar(next, marks);
}

/// Walks every ray of the block on `path`; marks and returns as walk_linear_rays().
template <class Marks>
std::size_t walk_ray_block(WalkPath path, const RayBlock& block, Marks marks) {
#if KNNOCC_AVX2_LANES
  if (path == WalkPath::avx512_bundles) return avx512_bundles::walk_block(block, marks);
#endif
  BlockRays rays(block);
  return walk_linear_rays(path, rays, marks);
}

/// setup_linear_ray() for rays[0..n) (1 <= n <= RayBlock::kRays) into `block`, eight at a time
/// on AVX2 machines; closes the block (RayBlock::close). Never inlined: the AVX-512 walk's target
/// enables FMA, and contracting OctoMap's float arithmetic inside it (-ffp-contract=fast, GCC's
/// default for gnu++17, or clang's default "on") would change bits; compiled on its own it keeps
/// the caller's flags.
template <class Key>
KNNOCC_NOINLINE void setup_ray_block(const Grid<Key>& grid, const RayFan& fan, const RayEnd* rays,
                                     std::size_t n, RayBlock& block) {
  std::size_t i = 0;
#if KNNOCC_AVX2_LANES
  if (cpu_has_avx2())
    for (; i + 8 <= n; i += 8) setup_linear_rays8<Key>(fan, rays + i, block, i);
#endif
  for (; i < n; ++i) {
    LinearRay r;
    setup_linear_ray(grid, fan, rays[i], r);
    block.set(i, r);
  }
  block.close(n);
}

/// setup_ray_block() for any number of rays, into LinearRays (tests and benchmarks).
template <class Key>
void setup_linear_rays(const Grid<Key>& grid, const RayFan& fan, const RayEnd* rays, std::size_t n,
                       LinearRay* out) {
  const auto block = std::make_unique<RayBlock>();
  for (std::size_t first = 0; first < n; first += RayBlock::kRays) {
    const std::size_t count = std::min(RayBlock::kRays, n - first);
    setup_ray_block(grid, fan, rays + first, count, *block);
    for (std::size_t i = 0; i < count; ++i) out[first + i] = block->get(i);
  }
}

/// Walks the rays that more(first, last) hands out (a range of RayEnds at a time; false when there
/// are none left) on `path`, set up a block at a time in `block`: independent set-ups (divisions,
/// a square root) overlap in the CPU. With bundles each block is walked whole; otherwise the
/// blocks' rays go on as one stream, whose lanes do not wait for each other. Returns the voxels
/// visited.
template <class Key, class More, class Marks>
std::size_t walk_fan(WalkPath path, const Grid<Key>& grid, const RayFan& fan, RayBlock& block,
                     More&& more, Marks marks) {
  constexpr std::size_t kBlock = RayBlock::kRays;
  const RayEnd *pos = nullptr, *stop = nullptr;
  if (path == WalkPath::avx512_bundles) {
    std::size_t visits = 0;
    while (more(pos, stop))
      for (; pos != stop; pos += block.size) {
        setup_ray_block(grid, fan, pos, std::min(kBlock, static_cast<std::size_t>(stop - pos)),
                        block);
        visits += walk_ray_block(path, block, marks);
      }
    return visits;
  }
  std::size_t taken = 0;
  block.size = 0;
  LinearRay ray;
  auto next = [&]() -> const LinearRay* {
    if (taken == block.size) {
      while (pos == stop)  // an empty range just asks for the next one
        if (!more(pos, stop)) return nullptr;
      setup_ray_block(grid, fan, pos, std::min(kBlock, static_cast<std::size_t>(stop - pos)),
                      block);
      pos += block.size;
      taken = 0;
    }
    ray = block.get(taken++);
    return &ray;
  };
  return walk_linear_rays(path, next, marks);
}

}  // namespace knnocc::detail
