// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Phase 1 of a scan (ScanInserter): collect. OctoMap's computeUpdate, point by point: the
// max-range rule, the ray's end point and end voxel, the endpoint's key, and the key box of the
// scan. Each thread collects its share of the points into its own ScanPart; a scan's rays are the
// union of all parts' rays.
//
// Per point p (sensor at origin o):
//   |p - o| <= max_range (or max_range < 0): a ray from o to p, and p's voxel is a hit;
//   otherwise: only the ray truncated at max_range (its end voxel is not freed), no hit.
// NaN/Inf points are skipped and counted; an endpoint outside the key range gets no hit and no
// ray (OctoMap's behaviour) and is counted.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <iterator>
#include <type_traits>
#include <vector>

#include "../../core/config.hpp"
#include "../../core/detail/key_rounding.hpp"
#include "../../core/detail/simd_support.hpp"
#include "../../core/grid.hpp"
#include "../../core/point3.hpp"
#include "../../core/point_traits.hpp"
#include "../../raycast/dda.hpp"
#include "../../raycast/detail/linear_ray.hpp"
#include "../../raycast/detail/scan_bitmap.hpp"
#include "../../sensor/endpoint_rating.hpp"
#include "append_buffer.hpp"
#include "hit_codes.hpp"
#include "point_bounds.hpp"
#include "point_keys.hpp"

namespace knnocc::detail {

/// The sensor origin of a scan and its voxel.
struct ScanOrigin {
  Point3f point;
  std::int32_t key[3] = {0, 0, 0};
  bool in_range = false;  ///< the origin lies in the key range (else no ray is cast)

  template <class Key>
  static ScanOrigin of(const Grid<Key>& grid, const Point3f& p) {
    ScanOrigin o;
    o.point = p;
    Key k;
    o.in_range = grid.point_to_key(p, k);
    for (int a = 0; a < 3; ++a) o.key[a] = k[a];
    return o;
  }
};

/// A box of keys, lo and hi included (empty: lo > hi).
struct KeyBox {
  std::int64_t lo[3], hi[3];

  /// The empty box of keys of type Key.
  template <class Key>
  static KeyBox empty() {
    KeyBox b;
    for (int a = 0; a < 3; ++a) {
      b.lo[a] = Key::extent;
      b.hi[a] = -1;
    }
    return b;
  }
  /// The origin's voxel when it is in range, else the empty box.
  template <class Key>
  static KeyBox around(const ScanOrigin& o) {
    if (!o.in_range) return empty<Key>();
    KeyBox b;
    for (int a = 0; a < 3; ++a) b.lo[a] = b.hi[a] = o.key[a];
    return b;
  }
  void extend(const std::int64_t (&k)[3]) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], k[a]);
      hi[a] = std::max(hi[a], k[a]);
    }
  }
  /// The smallest box holding both (an empty box adds nothing).
  void merge(const KeyBox& b) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], b.lo[a]);
      hi[a] = std::max(hi[a], b.hi[a]);
    }
  }
};

/// What counting a scan's points found (part of ScanStats).
struct PointCounts {
  std::size_t points = 0, nonfinite = 0, out_of_range = 0, beyond_max_range = 0;

  PointCounts& operator+=(const PointCounts& o) {
    points += o.points;
    nonfinite += o.nonfinite;
    out_of_range += o.out_of_range;
    beyond_max_range += o.beyond_max_range;
    return *this;
  }
};

/// What one thread collected from its share of the points.
struct ScanPart {
  AppendBuffer<RayEnd> rays;         // the rays that visit at least one voxel
  AppendBuffer<std::uint64_t> hits;  // endpoint keys, packed (Key::pack)
  std::vector<float> hit_logodds;    // insert_rated: the log-odds of each hit
  KeyBox box;                        // key box of origin, ray ends and hits
  std::size_t steps = 0;             // sum of |end - origin|_1 over the rays
  PointCounts counts;

  template <class Key>
  void start(const ScanOrigin& o) {
    rays.clear();
    hits.clear();
    hit_logodds.clear();
    steps = 0;
    counts = PointCounts{};
    box = KeyBox::around<Key>(o);
  }
};

/// What phase 1 hands to the next phases: the parts' totals.
struct CollectedScan {
  KeyBox box;                ///< key box of origin, ray ends and hits over all parts
  std::size_t steps = 0;     ///< sum of |end - origin|_1 over all rays
  std::size_t rays = 0;      ///< rays over all parts
  std::size_t hits = 0;      ///< hits over all parts
  std::size_t crossing = 0;  ///< clipped scans: rays walked alone (clip.hpp), not in `rays`
  PointCounts counts;
};

/// Key::pack() of per-axis indices.
template <class Key>
std::uint64_t pack_key(const std::int64_t (&k)[3]) {
  return (static_cast<std::uint64_t>(k[0]) << (2 * Key::depth)) |
         (static_cast<std::uint64_t>(k[1]) << Key::depth) | static_cast<std::uint64_t>(k[2]);
}

/// Iterators over Point3f in contiguous storage (std::vector, a pointer): the vectorised loops.
template <class It>
constexpr bool contiguous_point3f =
    std::is_same_v<It, const Point3f*> || std::is_same_v<It, Point3f*> ||
    std::is_same_v<It, typename std::vector<Point3f>::const_iterator> ||
    std::is_same_v<It, typename std::vector<Point3f>::iterator>;

template <class Points>
using iterator_of = decltype(std::begin(std::declval<const Points&>()));

template <class Points>
constexpr bool random_access_points =
    std::is_base_of_v<std::random_access_iterator_tag,
                      typename std::iterator_traits<iterator_of<Points>>::iterator_category>;

/// OctoMap's computeUpdate, point by point, into one ScanPart.
template <class Key>
struct Collector {
  const ScanOrigin origin;  // a copy: the loops store through pointers it might alias otherwise
  const double max_range;
  const KeyRounding<Key> rounding;
  ScanPart& part;
  // Chunks (add_chunk): the thread's hit bitmap, which takes the hits in place of part.hits; or,
  // with hit_codes set, their codes appended to hit_list.
  ScanBitmap* hit_map = nullptr;
  const HitCodes* hit_codes = nullptr;
  AppendBuffer<std::uint32_t>* hit_list = nullptr;

  // What a loop over points counts, in registers while it runs (the part's fields are stored to
  // after every point otherwise: the compiler cannot tell them from the buffers' contents).
  struct Tally {
    KeyBox box;
    std::size_t steps = 0;
    PointCounts counts;
    std::uint64_t* hit = nullptr;  // the next hit and ray go here (room made by the caller)
    RayEnd* ray = nullptr;
    std::uint32_t* code = nullptr;  // chunks with hit_codes: the next hit's code goes here
    std::uint32_t last_code = ~std::uint32_t{0};  // ...unless it repeats this one (no code is ~0)
  };
  Tally start() const {
    Tally t;
    t.box = part.box;
    return t;
  }
  void finish(const Tally& t) {
    if (t.hit) part.hits.set_end(t.hit);  // null: add_chunk, whose hits went to hit_map
    if (t.code) hit_list->set_end(t.code);
    part.rays.set_end(t.ray);
    part.box = t.box;
    part.steps += t.steps;
    part.counts += t.counts;
  }

  /// Points [first, last); rating: null, or the rating of *first (one per point from there on).
  template <class It>
  void add_points(It first, It last, const EndpointRating* rating) {
    if (rating)
      add_points<true>(first, last, rating);
    else
      add_points<false>(first, last, nullptr);
  }
  /// A chunk of a large scan: the hits straight into hit_map, and neither the key box nor the steps
  /// (the box is known before the points are collected).
  template <class It>
  void add_chunk(It first, It last) {
    add_points<false, true>(first, last, nullptr);
  }

  template <bool Rated, bool Chunk = false, class It>
  void add_points(It first, It last, const EndpointRating* rating) {
    // At most one hit and one ray per point: room for them first, then plain stores.
    const auto n = static_cast<std::size_t>(std::distance(first, last));
    Tally t = start();
    if (!Chunk) t.hit = part.hits.room_for(n);
    if (Chunk && hit_codes) t.code = hit_list->room_for(n);
    t.ray = part.rays.room_for(n);
#if KNNOCC_AVX2_LANES
    // Chunks of contiguous Point3f without max_range: the keys eight points at a time.
    if constexpr (Chunk && !Rated && contiguous_point3f<It>) {
      if (max_range < 0.0 && n >= 8 && cpu_has_avx2()) {
        const Point3f* p = &*first;
        std::size_t i = 0;
        for (; i + 8 <= n; i += 8) {
          std::int32_t key[3][8];
          if (!point_keys8<Key>(p + i, rounding.inverse_resolution(), key)) {
            for (std::size_t j = i; j < i + 8; ++j) add_one<Rated, Chunk>(p[j], nullptr, t);
            continue;
          }
          t.counts.points += 8;
          for (int j = 0; j < 8; ++j) {
            const std::int64_t k[3] = {key[0][j], key[1][j], key[2][j]};
            chunk_hit(k, t);
            add_ray<false, Chunk>(p[i + static_cast<std::size_t>(j)], k, t);
          }
        }
        first += static_cast<std::ptrdiff_t>(i);
      }
    }
#endif
    for (; first != last; ++first)
      add_one<Rated, Chunk>(to_point3f(*first), Rated ? rating++ : nullptr, t);
    finish(t);
  }

  template <bool Rated, bool Chunk>
  KNNOCC_ALWAYS_INLINE void add_one(const Point3f& q, const EndpointRating* r, Tally& t) {
    ++t.counts.points;
    if (!finite(q)) {
      ++t.counts.nonfinite;
      return;
    }
    add<Rated, Chunk>(q, r, t);
  }

  template <bool Rated, bool Chunk = false>
  KNNOCC_ALWAYS_INLINE void add(const Point3f& p, const EndpointRating* r, Tally& t) {
    const Point3f& o = origin.point;
    std::int64_t k[3];
    if (max_range < 0.0 || octomap_norm(p.x - o.x, p.y - o.y, p.z - o.z) <= max_range) {
      if (!rounding.point_to_key(p, k)) {
        ++t.counts.out_of_range;  // OctoMap's ray check fails on the same endpoint
        return;
      }
      // Even when the origin is out of range, as OctoMap.
      if constexpr (Chunk) {
        chunk_hit(k, t);
      } else {
        *t.hit++ = pack_key<Key>(k);
        t.box.extend(k);
      }
      if constexpr (Rated) {
        part.hit_logodds.push_back(r->logodds);
        if (!r->casts_ray) return;
      }
      add_ray<false, Chunk>(p, k, t);  // the box holds k already
    } else {
      ++t.counts.beyond_max_range;
      if constexpr (Rated)
        if (!r->casts_ray) return;
      const Point3f e = truncate_ray(o, p, max_range);
      if (rounding.point_to_key(e, k)) add_ray<!Chunk, Chunk>(e, k, t);
    }
  }

  KNNOCC_ALWAYS_INLINE void chunk_hit(const std::int64_t (&k)[3], Tally& t) {
    if (t.code) {  // a repeat of the previous hit (neighbouring points) is not stored again
      const std::uint32_t c = hit_codes->code(k);
      *t.code = c;
      t.code += c != t.last_code;
      t.last_code = c;
    } else {
      set_bit(hit_map->words(), hit_map->index(k[0], k[1], k[2]));
    }
  }

  // Keeps the rays that visit at least one voxel (start_ray() == RayStart::walk).
  template <bool ExtendBox, bool Chunk = false>
  KNNOCC_ALWAYS_INLINE void add_ray(const Point3f& end, const std::int64_t (&k)[3], Tally& t) {
    const std::int32_t(&ko)[3] = origin.key;
    if (!origin.in_range || (k[0] == ko[0] && k[1] == ko[1] && k[2] == ko[2])) return;
    // Filled in place: a RayEnd built on the stack and copied made the CPU reload it through
    // narrower stores.
    RayEnd& ray = *t.ray++;
    ray.end = end;
    for (int a = 0; a < 3; ++a) ray.key[a] = static_cast<std::int32_t>(k[a]);
    if (ExtendBox) t.box.extend(k);
    if (!Chunk)
      t.steps += static_cast<std::size_t>(std::llabs(k[0] - ko[0]) + std::llabs(k[1] - ko[1]) +
                                          std::llabs(k[2] - ko[2]));
  }
};

/// discretize: the distinct endpoint voxels of the points, then their centres as the points (in
/// one thread). `keys` is scratch for the endpoint keys.
template <class Key, class Points>
void collect_discretized(const Grid<Key>& grid, const Points& points, Collector<Key> c,
                         std::vector<std::uint64_t>& keys) {
  keys.clear();
  auto t = c.start();
  for (const auto& p : points) {
    ++t.counts.points;
    const Point3f q = to_point3f(p);
    std::int64_t k[3];
    if (!finite(q))
      ++t.counts.nonfinite;
    else if (!c.rounding.point_to_key(q, k))
      ++t.counts.out_of_range;
    else
      keys.push_back(pack_key<Key>(k));
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  t.hit = c.part.hits.room_for(keys.size());
  t.ray = c.part.rays.room_for(keys.size());
  for (const std::uint64_t packed : keys) {
    const Key k = Key::unpack(packed);
    c.template add<false>(Point3f{static_cast<float>(grid.index_to_coord(k[0])),
                                  static_cast<float>(grid.index_to_coord(k[1])),
                                  static_cast<float>(grid.index_to_coord(k[2]))},
                          nullptr, t);
  }
  c.finish(t);
}

/// A large scan's point bounds over one thread's share (ScanInserter's chunked path).
struct PointBounds {
  static constexpr std::size_t kSample = 8;  // every 8th point's distance is summed
  float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  std::uint64_t sampled = 0;
};

/// The coordinate bounds of the finite points in [a, b) and the origin, and the sum of the L1
/// distances in voxels (rounded down, capped for max_range) from the origin of every kSample-th
/// point: an integer, so the same for any split between threads.
template <class It>
PointBounds point_bounds(It first, std::size_t a, std::size_t b, const Point3f& o,
                         double resolution, double max_range) {
  float lo[3] = {o.x, o.y, o.z}, hi[3] = {o.x, o.y, o.z};
  // Point3f in contiguous storage (std::vector, a pointer) whose points are all finite: the
  // vectorised loop. Otherwise, and for other point types and containers, point by point.
  bool done = false;
  if constexpr (contiguous_point3f<It>) {
    if (b > a) done = finite_bounds(&first[static_cast<std::ptrdiff_t>(a)], b - a, lo, hi);
  }
  for (std::size_t i = done ? b : a; i < b; ++i) {
    const Point3f p = to_point3f(first[static_cast<std::ptrdiff_t>(i)]);
    // A non-finite point counts as the origin, which the bounds hold already: no branch.
    const bool ok = finite(p);
    const float c[3] = {ok ? p.x : o.x, ok ? p.y : o.y, ok ? p.z : o.z};
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], c[k]);
      hi[k] = std::max(hi[k], c[k]);
    }
  }
  PointBounds out;
  for (int k = 0; k < 3; ++k) {
    out.lo[k] = lo[k];
    out.hi[k] = hi[k];
  }
  const double inv = 1.0 / resolution;
  for (std::size_t i = (a + PointBounds::kSample - 1) / PointBounds::kSample * PointBounds::kSample;
       i < b; i += PointBounds::kSample) {
    const Point3f p = to_point3f(first[static_cast<std::ptrdiff_t>(i)]);
    if (!finite(p)) continue;
    double d = std::fabs(p.x - o.x) + std::fabs(p.y - o.y) + std::fabs(p.z - o.z);
    if (max_range > 0) d = std::min(d, 1.7320508075688772 * max_range);  // L1 <= sqrt(3) L2
    out.sampled += static_cast<std::uint64_t>(std::min(d * inv, 1e15));
  }
  return out;
}

}  // namespace knnocc::detail
