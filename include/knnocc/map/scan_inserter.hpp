#pragma once
// ScanInserter: OctoMap's insertPointCloud(points, origin, max_range, discretize) on an
// OccupancyMap, with the same map as result.
//
// Per point p (sensor at origin o):
//   |p - o| <= max_range (or max_range < 0): the voxels from o up to p's voxel are free, p's voxel
//                                            is occupied;
//   otherwise: only the ray truncated at max_range frees voxels (its end voxel is not freed).
// Within one scan occupied wins over free and each voxel is updated at most once, so the result
// does not depend on point order. discretize = true first reduces the endpoints to the centres of
// their distinct voxels.
//
// Bad points never reach the map: NaN/Inf points are skipped and counted; an endpoint outside
// the key range gets no occupied update and no ray (OctoMap's behaviour), and is counted.
//
// One scan in three passes, each split between the threads (ScanInserter's `threads`):
//   1. collect: per point the max-range rule, the ray's end point and the hit key; the key box of
//      the scan. Threads take equal shares of the points (when the point container has random
//      access).
//   2. walk: every ray marks its voxels in a per-scan scratch: a dense bit (or, for free voxels
//      of small boxes on AVX-512 CPUs, byte) per voxel of the box (detail/scan_bitmap.hpp),
//      walked sixteen or four rays at a time (AVX-512 or AVX2, detail/ray_lanes.hpp) when the box
//      is small enough, else a hashed mask per touched brick.
//      Each thread takes chunks of rays into its own scratch; free and occupied are unions, so
//      the result does not depend on which thread walked which ray.
//      Large scans whose dense box is known in advance run 1 and 2 a chunk of points at a time
//      (insert_chunked): each thread takes chunks in turn, collects them (the hits straight into
//      its hit bitmap) and walks their rays into its own scratch, all in one run of the threads;
//      this bounds the per-point buffers.
//   3. apply: the touched bricks with the thread scratches OR-ed, gathered in z, y, x brick order
//      whatever the path or thread count; the missing map bricks created in that order (one
//      thread), then every touched voxel updated exactly once, occupied first (each brick by one
//      thread).
// The scratch is kept between scans, so a warmed-up inserter allocates nothing per scan.
//
// Thread safety: an inserter is one writer (of its map); use one per thread, on different maps.
// With threads > 1 it runs its own workers inside each call and returns when they are done.
//
// insert_rated() is the same scan with a per-endpoint sensor model (KnnModel, eq 13-15): each
// endpoint brings its own occupied log-odds and its own "casts a free ray" decision; a voxel
// holding endpoints receives the sum of their log-odds (eq 15) and no free update (occupied wins),
// free voxels receive the model's miss_logodds() once per scan.

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <iterator>
#include <memory>
#include <type_traits>
#include <utility>
#include <vector>

#include "../core/config.hpp"
#include "../core/point3.hpp"
#include "../core/point_traits.hpp"
#include "../detail/append_buffer.hpp"
#include "../detail/flat_index.hpp"
#include "../detail/huge_pages.hpp"
#include "../detail/key_rounding.hpp"
#include "../detail/point_bounds.hpp"
#include "../detail/point_keys.hpp"
#include "../detail/ray_lanes.hpp"
#include "../detail/scan_bitmap.hpp"
#include "../detail/thread_pool.hpp"
#include "../raycast/dda.hpp"
#include "../sensor/endpoint_rating.hpp"
#include "../sensor/octomap_model.hpp"
#include "occupancy_map.hpp"

namespace knnocc {

namespace detail {
template <class T, class = void>
struct has_size : std::false_type {};
template <class T>
struct has_size<T, std::void_t<decltype(std::declval<const T&>().size())>> : std::true_type {};
}  // namespace detail

/// What one insert_point_cloud call did.
struct ScanStats {
  std::size_t points = 0;            ///< points given
  std::size_t nonfinite = 0;         ///< skipped: NaN or Inf coordinate
  std::size_t out_of_range = 0;      ///< endpoints outside the key range (no update from them)
  std::size_t beyond_max_range = 0;  ///< points farther than max_range (truncated free ray only)
  std::size_t ray_keys = 0;          ///< voxels visited by rays, before de-duplication
  std::size_t occupied_voxels = 0;   ///< voxels that received the hit update (or a rated sum)
  std::size_t free_voxels = 0;       ///< voxels that received the miss update
  bool origin_valid = true;          ///< false: origin NaN/Inf, nothing was inserted
  /// Pieces the points were collected and walked in (0: the origin was not finite). A scan of more
  /// than ScanInserter::chunk_points (4096) points in a random-access container (not discretized,
  /// not rated) whose dense box fits goes that many points at a time, which bounds the per-point
  /// buffers; the map gets the same updates either way.
  std::size_t chunks = 0;
  /// The walk marked free voxels in a byte per voxel rather than a bit (on AVX-512 CPUs, a scan
  /// whose dense box has at most 4 M voxels and whose rays take at least 4 M steps; faster, the
  /// same map).
  bool byte_marks = false;
};

template <class Key = OcKey, class Model = OctoMapModel>
class ScanInserter {
 public:
  using map_type = OccupancyMap<Key>;
  /// Points per chunk of a large scan (see ScanStats::chunks).
  static constexpr std::size_t chunk_points = 4096;

  /// threads: how many threads walk the rays of a scan (>= 1; the calling thread is one of them).
  /// The map is the same for every thread count.
  explicit ScanInserter(map_type& map, Model model = {}, unsigned threads = 1)
      : map_(&map), model_(model) {
    set_threads(threads);
  }
  ScanInserter(ScanInserter&&) noexcept = default;  // movable, not copyable (threads, scratch)
  ScanInserter& operator=(ScanInserter&&) noexcept = default;

  const Model& model() const { return model_; }
  map_type& map() { return *map_; }

  unsigned threads() const { return threads_; }
  /// Threads for the following scans (>= 1; 0 is rejected with std::invalid_argument).
  void set_threads(unsigned threads) {
    if (threads < 1) detail::invalid_argument("threads must be >= 1");
    if (threads == threads_) return;
    threads_ = threads;
    pool_.reset();
    while (workers_.size() < threads_) workers_.push_back(std::make_unique<Worker>());
  }

  /// Address space the dense per-scan scratch may take, all threads together (default 384 MB,
  /// two bitmaps per thread: two threads keep the boxes that fitted 256 MB when a scan had one
  /// bitmap per thread and one shared; pages no ray touches stay unmapped, so resident memory is
  /// usually far less; a box marked in bytes, ScanStats::byte_marks, takes 9 bits per voxel instead
  /// of 2 and falls back to bits when the limit is too small for bytes). A scan whose box needs
  /// more uses the hashed scratch (slower, same map); 0 always does.
  void set_scratch_limit(std::size_t bytes) { scratch_limit_ = bytes; }
  std::size_t scratch_limit() const { return scratch_limit_; }

  /// Inserts one scan of world-frame points seen from `origin`. max_range < 0: no limit;
  /// max_range == 0 or NaN is rejected (std::invalid_argument; abort without exceptions).
  template <class Points, class Origin>
  ScanStats insert_point_cloud(const Origin& origin, const Points& points, double max_range = -1.0,
                               bool discretize = false) {
    if (max_range == 0.0 || std::isnan(max_range))
      detail::invalid_argument("max_range must be > 0, or < 0 for no limit");
    ScanStats st;
    origin_ = to_point3f(origin);
    if (!detail::finite(origin_)) {
      st.origin_valid = false;
      for (const auto& p : points) (void)p, ++st.points;
      return st;
    }
    rated_ = false;
    hit_l_ = model_.hit_logodds();
    miss_l_ = model_.miss_logodds();
    if constexpr (random_access<Points>) {
      if (!discretize && insert_chunked(points, max_range, st)) return st;
    }
    collect(points, max_range, discretize, nullptr, st);
    walk(st);
    st.chunks = 1;
    return st;
  }

  /// Eq 15 scan: ratings[i] rates points[i] (same length, else std::invalid_argument). A point
  /// within max_range adds ratings[i].logodds to its voxel's sum; any point casts its ray (for a
  /// point beyond max_range the ray truncated at max_range) only if ratings[i].casts_ray. Voxels
  /// holding endpoints get their sum, rounded to float once (summed in double in point order);
  /// voxels crossed by rays and holding no endpoint get model().miss_logodds(). Non-finite and
  /// out-of-range points are skipped and counted as in insert_point_cloud.
  template <class Points, class Origin>
  ScanStats insert_rated(const Origin& origin, const Points& points,
                         const std::vector<EndpointRating>& ratings, double max_range = -1.0) {
    if (max_range == 0.0 || std::isnan(max_range))
      detail::invalid_argument("max_range must be > 0, or < 0 for no limit");
    const auto n = static_cast<std::size_t>(std::distance(std::begin(points), std::end(points)));
    if (n != ratings.size())
      detail::invalid_argument("insert_rated: one rating per point expected");
    ScanStats st;
    origin_ = to_point3f(origin);
    if (!detail::finite(origin_)) {
      st.origin_valid = false;
      st.points = n;
      return st;
    }
    rated_ = true;
    miss_l_ = model_.miss_logodds();
    collect(points, max_range, false, ratings.data(), st);
    walk(st);
    st.chunks = 1;
    return st;
  }

 private:
  using layout = BrickLayout<Key>;

  // A ray that visits at least one voxel; its end voxel as plain integers (a Key rebuilt
  // through memory per point made the CPU wait on narrower stores).
  using Ray = detail::RayEnd;
  struct BrickUpdate {  // one touched brick of this scan and, once created, its map slot
    std::uint64_t coord;
    std::uint32_t slot;
    VoxelMask hit, miss;
  };
  struct Scratch {  // hashed path: one touched brick
    std::uint64_t coord = 0;
    VoxelMask hit, miss;
  };
  // What one thread collected from its share of the points.
  struct Part {
    detail::AppendBuffer<Ray> rays;            // the rays that visit at least one voxel
    detail::AppendBuffer<std::uint64_t> hits;  // occupied endpoint keys, packed
    std::vector<float> hit_logodds;            // insert_rated: the log-odds of each hit
    std::int64_t key_min[3], key_max[3];       // key box of origin, ray ends and hits
    std::size_t steps = 0;                     // sum of |end - origin|_1 over the rays
    ScanStats st;                              // points, nonfinite, out_of_range, beyond_max_range

    void clear() {
      rays.clear();
      hits.clear();
      hit_logodds.clear();
      steps = 0;
      st = ScanStats{};
    }
  };

  // A large scan's point bounds over one thread's share (insert_chunked).
  struct Bounds {
    static constexpr std::size_t kSample = 8;  // every 8th point's distance is summed
    float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    std::uint64_t sampled = 0;
  };

  // One thread's scratch (separate allocations, so threads do not share cache lines).
  struct Worker {
    detail::ScanBitmap hit, miss;  // dense path: this thread's endpoints and free voxels
    std::unique_ptr<detail::RayBlock> block = std::make_unique<detail::RayBlock>();
    detail::FlatIndex index;  // hashed path: brick coordinate -> slot in scratch
    std::vector<Scratch> scratch;
    std::size_t used = 0;
    std::uint64_t last_coord = 0;
    std::uint32_t last = detail::FlatIndex::kNone;
    std::size_t visits = 0;
    std::vector<VoxelMask> row_hit, row_miss;       // dense apply: one brick row
    std::size_t occupied = 0, free = 0, added = 0;  // apply: this thread's updates
    Part part;                                      // collect: this thread's share
    Bounds bounds;                                  // insert_chunked: its share's bounds

    Scratch& scratch_for(std::uint64_t c) {
      if (last != detail::FlatIndex::kNone && c == last_coord) return scratch[last];
      bool inserted = false;
      last = index.find_or_insert(c, static_cast<std::uint32_t>(used), inserted);
      last_coord = c;
      if (inserted) {
        if (used == scratch.size()) scratch.emplace_back();
        Scratch& s = scratch[used++];
        s.coord = c;
        s.hit.clear();
        s.miss.clear();
      }
      return scratch[last];
    }
    void reset_hashed() {
      used = 0;
      index.clear();
      last = detail::FlatIndex::kNone;
    }
  };

  template <class P>
  static Point3f to_point3f(const P& p) {
    return detail::to_point3f(p);
  }

  // ---- 1. collect -----------------------------------------------------------------------

  // Iterators over Point3f in contiguous storage (std::vector, a pointer): the vectorised loops.
  template <class It>
  static constexpr bool contiguous_point3f =
      std::is_same_v<It, const Point3f*> || std::is_same_v<It, Point3f*> ||
      std::is_same_v<It, typename std::vector<Point3f>::const_iterator> ||
      std::is_same_v<It, typename std::vector<Point3f>::iterator>;

  // OctoMap's computeUpdate, point by point, into one Part.
  struct Collector {
    const Point3f origin;
    const std::int32_t (&origin_key)[3];
    const bool origin_in_range;
    const double max_range;
    const detail::KeyRounding<Key> rounding;
    Part& part;
    // add_chunk: the thread's hit bitmap, which takes the hits in place of part.hits.
    detail::ScanBitmap* hit_map = nullptr;

    // What a loop over points counts, in registers while it runs (the Part's fields are stored
    // to after every point otherwise: the compiler cannot tell them from the buffers' contents).
    struct Tally {
      std::int64_t lo[3], hi[3];  // key box
      std::size_t steps = 0, points = 0, nonfinite = 0, out_of_range = 0, beyond_max_range = 0;
      std::uint64_t* hit = nullptr;  // the next hit and ray go here (room made by the caller)
      Ray* ray = nullptr;
    };
    Tally start() const {
      Tally t;
      for (int a = 0; a < 3; ++a) {
        t.lo[a] = part.key_min[a];
        t.hi[a] = part.key_max[a];
      }
      return t;
    }
    void finish(const Tally& t) {
      if (t.hit) part.hits.set_end(t.hit);  // null: add_chunk, whose hits went to hit_map
      part.rays.set_end(t.ray);
      for (int a = 0; a < 3; ++a) {
        part.key_min[a] = t.lo[a];
        part.key_max[a] = t.hi[a];
      }
      part.steps += t.steps;
      part.st.points += t.points;
      part.st.nonfinite += t.nonfinite;
      part.st.out_of_range += t.out_of_range;
      part.st.beyond_max_range += t.beyond_max_range;
    }

    // rating: null, or the rating of *first (one per point from there on).
    template <class It>
    void add_points(It first, It last, const EndpointRating* rating) {
      if (rating)
        add_points<true>(first, last, rating);
      else
        add_points<false>(first, last, nullptr);
    }
    // insert_chunked: the hits straight into hit_map, and neither the key box nor the steps
    // (the box is known before the points are collected).
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
      t.ray = part.rays.room_for(n);
#if KNNOCC_AVX2_LANES
      // Chunks of contiguous Point3f without max_range: the keys eight points at a time.
      if constexpr (Chunk && !Rated && contiguous_point3f<It>) {
        if (max_range < 0.0 && n >= 8 && detail::cpu_has_avx2()) {
          const Point3f* p = &*first;
          std::size_t i = 0;
          for (; i + 8 <= n; i += 8) {
            std::int32_t key[3][8];
            if (!detail::point_keys8<Key>(p + i, rounding.inverse_resolution(), key)) {
              for (std::size_t j = i; j < i + 8; ++j) add_one<Rated, Chunk>(p[j], nullptr, t);
              continue;
            }
            t.points += 8;
            for (int j = 0; j < 8; ++j) {
              const std::int64_t k[3] = {key[0][j], key[1][j], key[2][j]};
              detail::set_bit(hit_map->words(), hit_map->index(k[0], k[1], k[2]));
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
      ++t.points;
      if (!detail::finite(q)) {
        ++t.nonfinite;
        return;
      }
      add<Rated, Chunk>(q, r, t);
    }

    template <bool Rated, bool Chunk = false>
    KNNOCC_ALWAYS_INLINE void add(const Point3f& p, const EndpointRating* r, Tally& t) {
      const Point3f& o = origin;
      std::int64_t k[3];
      if (max_range < 0.0 || detail::octomap_norm(p.x - o.x, p.y - o.y, p.z - o.z) <= max_range) {
        if (!rounding.point_to_key(p, k)) {
          ++t.out_of_range;  // OctoMap's ray check fails on the same endpoint
          return;
        }
        // Even when the origin is out of range, as OctoMap.
        if constexpr (Chunk) {
          detail::set_bit(hit_map->words(), hit_map->index(k[0], k[1], k[2]));
        } else {
          *t.hit++ = pack(k);
          extend_box(k, t);
        }
        if constexpr (Rated) {
          part.hit_logodds.push_back(r->logodds);
          if (!r->casts_ray) return;
        }
        add_ray<false, Chunk>(p, k, t);  // the box holds k already
      } else {
        ++t.beyond_max_range;
        if constexpr (Rated)
          if (!r->casts_ray) return;
        const Point3f e = truncate_ray(o, p, max_range);
        if (rounding.point_to_key(e, k)) add_ray<!Chunk, Chunk>(e, k, t);
      }
    }

    // Keeps the rays that visit at least one voxel (start_ray() == RayStart::walk).
    template <bool ExtendBox, bool Chunk = false>
    KNNOCC_ALWAYS_INLINE void add_ray(const Point3f& end, const std::int64_t (&k)[3], Tally& t) {
      if (!origin_in_range ||
          (k[0] == origin_key[0] && k[1] == origin_key[1] && k[2] == origin_key[2]))
        return;
      // Filled in place: a Ray built on the stack and copied made the CPU reload it through
      // narrower stores.
      Ray& ray = *t.ray++;
      ray.end = end;
      for (int a = 0; a < 3; ++a) ray.key[a] = static_cast<std::int32_t>(k[a]);
      if (ExtendBox) extend_box(k, t);
      if (!Chunk)
        t.steps += static_cast<std::size_t>(std::llabs(k[0] - origin_key[0]) +
                                            std::llabs(k[1] - origin_key[1]) +
                                            std::llabs(k[2] - origin_key[2]));
    }

    static KNNOCC_ALWAYS_INLINE void extend_box(const std::int64_t (&k)[3], Tally& t) {
      for (int a = 0; a < 3; ++a) {
        t.lo[a] = std::min(t.lo[a], k[a]);
        t.hi[a] = std::max(t.hi[a], k[a]);
      }
    }
  };

  static std::uint64_t pack(const std::int64_t (&k)[3]) {  // Key::pack()
    return (static_cast<std::uint64_t>(k[0]) << (2 * Key::depth)) |
           (static_cast<std::uint64_t>(k[1]) << Key::depth) | static_cast<std::uint64_t>(k[2]);
  }

  template <class Points>
  using iterator_of = decltype(std::begin(std::declval<const Points&>()));

  template <class Points>
  static constexpr bool random_access =
      std::is_base_of_v<std::random_access_iterator_tag,
                        typename std::iterator_traits<iterator_of<Points>>::iterator_category>;

  // Fills the workers' Parts (in parallel when the points allow random access) and merges their
  // boxes and counts: the scan's rays are the union of all Parts' rays.
  template <class Points>
  void collect(const Points& points, double max_range, bool discretize,
               const EndpointRating* ratings, ScanStats& st) {
    start_collect();
    if (discretize) {
      collect_discretized(points, collector(0, max_range));
    } else if constexpr (random_access<Points>) {
      const auto first = std::begin(points);
      collect_range(first, static_cast<std::size_t>(std::distance(first, std::end(points))),
                    max_range, ratings);
    } else {
      collector(0, max_range).add_points(std::begin(points), std::end(points), ratings);
    }
    merge_parts(st, true);
  }

  // The origin's key; empty Parts.
  void start_collect() {
    Key ko;
    origin_in_range_ = map_->grid().point_to_key(origin_, ko);
    for (int a = 0; a < 3; ++a) origin_key_[a] = ko[a];
    clear_parts();
  }
  void clear_parts() {
    for (unsigned w = 0; w < threads_; ++w) {
      Part& part = workers_[w]->part;
      part.clear();
      for (int a = 0; a < 3; ++a) {
        part.key_min[a] = origin_in_range_ ? origin_key_[a] : Key::extent;
        part.key_max[a] = origin_in_range_ ? origin_key_[a] : -1;
      }
    }
  }
  Collector collector(unsigned w, double max_range) {
    return Collector{origin_,
                     origin_key_,
                     origin_in_range_,
                     max_range,
                     detail::KeyRounding<Key>(map_->grid()),
                     workers_[w]->part};
  }

  // Points [first, first + n) into the Parts: equal shares per thread (one thread for few points).
  template <class It>
  void collect_range(It first, std::size_t n, double max_range, const EndpointRating* ratings) {
    const unsigned parts = n >= kThreadedPoints ? threads_ : 1;
    auto job = [&](unsigned w) {
      if (w >= parts) return;
      const std::size_t a = n * w / parts, b = n * (w + 1) / parts;
      collector(w, max_range)
          .add_points(first + static_cast<std::ptrdiff_t>(a),
                      first + static_cast<std::ptrdiff_t>(b), ratings ? ratings + a : nullptr);
    };
    if (parts == 1)
      job(0u);
    else
      run(job);
  }

  // Sums the Parts' counts into st and the scan totals; `box`: the key box too.
  void merge_parts(ScanStats& st, bool box) {
    steps_ = 0;
    rays_total_ = hits_total_ = 0;
    if (box)
      for (int a = 0; a < 3; ++a) {
        key_min_[a] = Key::extent;
        key_max_[a] = -1;
      }
    for (unsigned w = 0; w < threads_; ++w) {
      const Part& part = workers_[w]->part;
      steps_ += part.steps;
      rays_total_ += part.rays.size();
      hits_total_ += part.hits.size();
      if (box)
        for (int a = 0; a < 3; ++a) {
          key_min_[a] = std::min(key_min_[a], part.key_min[a]);
          key_max_[a] = std::max(key_max_[a], part.key_max[a]);
        }
      st.points += part.st.points;
      st.nonfinite += part.st.nonfinite;
      st.out_of_range += part.st.out_of_range;
      st.beyond_max_range += part.st.beyond_max_range;
    }
  }

  // ---- large scans in chunks ------------------------------------------------------------
  //
  // The per-point buffers (rays and hits, 32 bytes a point) would outweigh a small map, so a large
  // scan whose dense box is known in advance goes through collect and walk a chunk of points at a
  // time, into the threads' bitmaps, and is applied once at the end: the same voxels, each updated
  // once, as in one piece. The box comes from the points' coordinate bounds, clipped to max_range
  // around the origin (keys are monotonic in coordinates; a ray truncated at max_range ends
  // between origin and point, within max_range of the origin), grown by a voxel for rounding.
  // Each thread takes chunks in turn and collects and walks them into its own bitmaps, all in one
  // run of the threads: small chunks keep the threads' shares even at the end of a scan.

  // The coordinate bounds of the finite points in [a, b) and the origin, and the sum of the L1
  // distances in voxels (rounded down, capped for max_range) from the origin of every kSample-th
  // point: an integer, so the same for any split between threads.
  template <class It>
  Bounds point_bounds(It first, std::size_t a, std::size_t b, double max_range) const {
    const Point3f o = origin_;
    float lo[3] = {o.x, o.y, o.z}, hi[3] = {o.x, o.y, o.z};
    // Point3f in contiguous storage (std::vector, a pointer) whose points are all finite: the
    // vectorised loop. Otherwise, and for other point types and containers, point by point.
    bool done = false;
    if constexpr (contiguous_point3f<It>) {
      if (b > a)
        done = detail::finite_bounds(&first[static_cast<std::ptrdiff_t>(a)], b - a, lo, hi);
    }
    for (std::size_t i = done ? b : a; i < b; ++i) {
      const Point3f p = to_point3f(first[static_cast<std::ptrdiff_t>(i)]);
      // A non-finite point counts as the origin, which the bounds hold already: no branch.
      const bool ok = detail::finite(p);
      const float c[3] = {ok ? p.x : o.x, ok ? p.y : o.y, ok ? p.z : o.z};
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], c[k]);
        hi[k] = std::max(hi[k], c[k]);
      }
    }
    Bounds out;
    for (int k = 0; k < 3; ++k) {
      out.lo[k] = lo[k];
      out.hi[k] = hi[k];
    }
    const double inv = 1.0 / map_->resolution();
    for (std::size_t i = (a + Bounds::kSample - 1) / Bounds::kSample * Bounds::kSample; i < b;
         i += Bounds::kSample) {
      const Point3f p = to_point3f(first[static_cast<std::ptrdiff_t>(i)]);
      if (!detail::finite(p)) continue;
      double d = std::fabs(p.x - o.x) + std::fabs(p.y - o.y) + std::fabs(p.z - o.z);
      if (max_range > 0) d = std::min(d, 1.7320508075688772 * max_range);  // L1 <= sqrt(3) L2
      out.sampled += static_cast<std::uint64_t>(std::min(d * inv, 1e15));
    }
    return out;
  }

  template <class Points>
  bool insert_chunked(const Points& points, double max_range, ScanStats& st) {
    const auto first = std::begin(points);
    const auto n = static_cast<std::size_t>(std::distance(first, std::end(points)));
    if (n <= chunk_points) return false;
    start_collect();
    if (!origin_in_range_) return false;
    // The points' bounds (and a sample of the rays' lengths in voxels for dense_fits, which only
    // picks the faster path), each thread over its share of the points.
    const unsigned parts = n >= kThreadedPoints ? threads_ : 1;
    auto bound = [&](unsigned w) {
      if (w < parts)
        workers_[w]->bounds = point_bounds(first, n * w / parts, n * (w + 1) / parts, max_range);
    };
    if (parts == 1)
      bound(0u);
    else
      run(bound);
    float lo[3] = {origin_.x, origin_.y, origin_.z}, hi[3] = {origin_.x, origin_.y, origin_.z};
    std::uint64_t sampled = 0;
    for (unsigned w = 0; w < parts; ++w) {
      const Bounds& b = workers_[w]->bounds;
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], b.lo[a]);
        hi[a] = std::max(hi[a], b.hi[a]);
      }
      sampled += b.sampled;
    }
    if (max_range > 0) {  // rays end within max_range of the origin (truncated past it)
      const float o[3] = {origin_.x, origin_.y, origin_.z};
      const auto r = detail::to_float(max_range);
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::max(lo[a], o[a] - r);
        hi[a] = std::min(hi[a], o[a] + r);
      }
    }
    Key klo, khi;
    if (!map_->grid().point_to_key(Point3f{lo[0], lo[1], lo[2]}, klo) ||
        !map_->grid().point_to_key(Point3f{hi[0], hi[1], hi[2]}, khi))
      return false;  // points outside the key range: the one-piece path counts them
    for (int a = 0; a < 3; ++a) {
      key_min_[a] = std::int64_t{klo[a]} - 1;
      key_max_[a] = std::int64_t{khi[a]} + 1;
    }
    steps_ = static_cast<std::size_t>(sampled * Bounds::kSample);
    if (!dense_fits()) return false;

    st.byte_marks = byte_marks_;
    prepare_dense();
    const detail::RayFan fan = dense_fan();
    const std::size_t chunks = (n + chunk_points - 1) / chunk_points;
    for (unsigned w = 0; w < threads_; ++w)  // here: a thread may get no chunk of this scan
      workers_[w]->part.rays.reserve(chunk_points);
    next_chunk_->store(0, std::memory_order_relaxed);
    auto job = [&](unsigned w) {
      Worker& worker = *workers_[w];
      Part& part = worker.part;
      worker.visits = 0;
      for (std::size_t c; (c = next_chunk_->fetch_add(1, std::memory_order_relaxed)) < chunks;) {
        const std::size_t a = c * chunk_points, b = std::min(n, a + chunk_points);
        part.rays.clear();
        Collector collect_chunk = collector(w, max_range);
        collect_chunk.hit_map = &worker.hit;
        collect_chunk.add_chunk(first + static_cast<std::ptrdiff_t>(a),
                                first + static_cast<std::ptrdiff_t>(b));
        bool given = false;  // the chunk's rays, handed out once
        worker.visits += walk_dense_rays(worker, fan, [&](const Ray*& pos, const Ray*& stop) {
          pos = part.rays.data();
          stop = given ? pos : pos + part.rays.size();
          given = true;
          return pos != stop;
        });
      }
    };
    run(job);
    merge_parts(st, false);  // each Part counted the points of all its chunks
    for (unsigned w = 0; w < threads_; ++w) st.ray_keys += workers_[w]->visits;
    st.chunks = chunks;
    apply_dense(st);
    return true;
  }

  // discretize: the distinct endpoint voxels, then their centres as the points (in one thread).
  template <class Points>
  void collect_discretized(const Points& points, Collector c) {
    const Grid<Key>& grid = map_->grid();
    endpoints_.clear();
    auto t = c.start();
    for (const auto& p : points) {
      ++t.points;
      const Point3f q = to_point3f(p);
      std::int64_t k[3];
      if (!detail::finite(q))
        ++t.nonfinite;
      else if (!c.rounding.point_to_key(q, k))
        ++t.out_of_range;
      else
        endpoints_.push_back(pack(k));
    }
    std::sort(endpoints_.begin(), endpoints_.end());
    endpoints_.erase(std::unique(endpoints_.begin(), endpoints_.end()), endpoints_.end());
    t.hit = c.part.hits.room_for(endpoints_.size());
    t.ray = c.part.rays.room_for(endpoints_.size());
    for (const std::uint64_t packed : endpoints_) {
      const Key k = Key::unpack(packed);
      c.template add<false>(Point3f{static_cast<float>(grid.index_to_coord(k[0])),
                                    static_cast<float>(grid.index_to_coord(k[1])),
                                    static_cast<float>(grid.index_to_coord(k[2]))},
                            nullptr, t);
    }
    c.finish(t);
  }

  // ---- 2. walk --------------------------------------------------------------------------

  void walk(ScanStats& st) {
    if (hits_total_ == 0 && rays_total_ == 0) return;
    if (dense_fits())
      walk_dense(st);
    else
      walk_hashed(st);
  }

  // Bits of dense scratch per ray step at most: beyond that, clearing and scanning the bitmap
  // would cost more than walking the rays.
  static constexpr std::int64_t kDenseBitsPerStep = 64;
  // The dense box is the key box of origin and end points grown by one voxel: per axis a walk
  // moves monotonically from the origin voxel and may pass the end voxel's border by rounding
  // (a crossing computed within the length), but never a second border: that would take an error
  // of a whole voxel in t, while the float direction and length err by about 1e-6 of the ray
  // length, under 0.2 voxel for the rays of a box edge below 2^16 voxels + 64.
  static constexpr std::int64_t kDenseMaxEdge = (std::int64_t{1} << 16) + 64;
  // Free voxels are marked in bytes, not bits, when the box has at most kByteMarkVoxels voxels
  // (a byte map of up to 4 MB per thread, taken 2 MB at a time) and the scan walks at least
  // kByteMarkSteps steps: a byte is marked by a plain store, where bits of neighbouring voxels
  // wait on each other's read-modify-writes of one word (detail/ray_lanes.hpp). On TUM at 0.05 m
  // (boxes of 0.6-3.2 M voxels, 5.2-7.6 M steps a scan) that took the insertion to 0.71 of its
  // time. Shorter walks gain too little for the memory: TUM at 0.1 m (2.6-3.8 M steps) would
  // have added up to 0.7 MB to a 1.8 MB peak. Larger boxes would not fit in the caches and would
  // multiply the scratch's resident memory by eight.
  static constexpr std::int64_t kByteMarkVoxels = std::int64_t{4} << 20;
  static constexpr std::size_t kByteMarkSteps = std::size_t{4} << 20;
  // Scans of fewer points are collected (and bounded) on one thread: waking the others costs more.
  static constexpr std::size_t kThreadedPoints = 2 * chunk_points;

  // Chooses the dense path and shapes its box: the key box grown by one voxel, brick aligned.
  bool dense_fits() {
    std::int64_t bits = 1;
    for (int a = 0; a < 3; ++a) {
      if (key_min_[a] < 1 || key_max_[a] > Key::extent - 2) return false;  // stay in key range
      box_lo_[a] = (key_min_[a] - 1) / kBrickEdge * kBrickEdge;
      const std::int64_t end = ((key_max_[a] + 1) / kBrickEdge + 1) * kBrickEdge;
      // Rows along x are whole 64-bit words (ScanBitmap::take_brick_row reads them so).
      const std::int64_t align = a == 0 ? 64 : kBrickEdge;
      box_size_[a] = (end - box_lo_[a] + align - 1) / align * align;
      if (box_size_[a] > kDenseMaxEdge) return false;
      bits *= box_size_[a];
    }
    // Two bitmaps per thread: occupied voxels in bits, free voxels in bytes when the box is small.
    const double limit = static_cast<double>(scratch_limit_) / threads_;
    byte_marks_ = detail::walks_bundles<detail::ByteMarks>() && bits <= kByteMarkVoxels &&
                  steps_ >= kByteMarkSteps && static_cast<double>(bits) / 8 * 9 <= limit;
    return static_cast<double>(bits) / 8 * (byte_marks_ ? 9 : 2) <= limit &&
           bits <= kDenseBitsPerStep * static_cast<std::int64_t>(steps_) + (std::int64_t{1} << 20);
  }

  void walk_dense(ScanStats& st) {
    st.byte_marks = byte_marks_;
    prepare_dense();
    mark_dense(st);
    apply_dense(st);
  }

  // The bitmaps of the dense box (box_lo_, box_size_), all zero.
  void prepare_dense() {
    for (unsigned w = 0; w < threads_; ++w) {
      workers_[w]->hit.reshape(box_lo_, box_size_);
      workers_[w]->miss.reshape(box_lo_, box_size_, byte_marks_);
    }
  }
  detail::RayFan dense_fan() const {
    const detail::ScanBitmap& bitmap = workers_[0]->miss;  // every thread's bitmaps alike
    return detail::RayFan(map_->grid(), origin_, origin_key_, box_lo_,
                          {bitmap.stride(0), bitmap.stride(1), bitmap.stride(2)});
  }

  // The Parts' hits and rays into the bitmaps: each thread its own Part's hits, and rays from
  // every Part in chunks.
  void mark_dense(ScanStats& st) {
    plan_chunks();
    const detail::RayFan fan = dense_fan();
    auto job = [&](unsigned w) {
      Worker& worker = *workers_[w];
      mark_hits(worker);
      worker.visits = walk_dense_rays(
          worker, fan, [this](const Ray*& pos, const Ray*& stop) { return next_rays(pos, stop); });
    };
    run(job);
    for (unsigned w = 0; w < threads_; ++w) st.ray_keys += workers_[w]->visits;
  }

  // The worker's Part's endpoints into its hit bitmap.
  static void mark_hits(Worker& worker) {
    for (const std::uint64_t packed : worker.part.hits) {
      const Key k = Key::unpack(packed);
      detail::set_bit(worker.hit.words(), worker.hit.index(k[0], k[1], k[2]));
    }
  }

  // Walks the rays that more(pos, stop) hands out (a range at a time, false when there are no
  // more) into the worker's miss bitmap; returns the voxels visited. Rays are set up a RayBlock at
  // a time: independent set-ups (divisions, a square root) overlap in the CPU, and go eight at a
  // time on AVX2 machines. The block is walked whole, or its rays go on as one stream with the
  // next blocks' (detail::walks_bundles).
  template <class More>
  std::size_t walk_dense_rays(Worker& worker, const detail::RayFan& fan, More&& more) {
    if (worker.miss.has_bytes())
      return walk_dense_rays(worker, fan, more, detail::ByteMarks{worker.miss.bytes()});
    return walk_dense_rays(worker, fan, more, detail::BitMarks{worker.miss.words()});
  }
  template <class More, class Marks>
  std::size_t walk_dense_rays(Worker& worker, const detail::RayFan& fan, More& more, Marks marks) {
    constexpr std::size_t kBlock = detail::RayBlock::kRays;
    detail::RayBlock& block = *worker.block;
    const Ray *pos = nullptr, *stop = nullptr;
    if (detail::walks_bundles<Marks>()) {
      std::size_t visits = 0;
      while (more(pos, stop))
        for (; pos != stop; pos += block.size) {
          detail::setup_ray_block(map_->grid(), fan, pos,
                                  std::min(kBlock, static_cast<std::size_t>(stop - pos)), block);
          visits += detail::walk_ray_block(block, marks);
        }
      return visits;
    }
    std::size_t taken = 0;
    block.size = 0;
    detail::LinearRay ray;
    auto next = [&]() -> const detail::LinearRay* {
      if (taken == block.size) {
        while (pos == stop)  // an empty range just asks for the next one
          if (!more(pos, stop)) return nullptr;
        detail::setup_ray_block(map_->grid(), fan, pos,
                                std::min(kBlock, static_cast<std::size_t>(stop - pos)), block);
        pos += block.size;
        taken = 0;
      }
      ray = block.get(taken++);
      return &ray;
    };
    return detail::walk_linear_rays(next, marks);
  }

  void walk_hashed(ScanStats& st) {
    for (unsigned w = 0; w < threads_; ++w) workers_[w]->reset_hashed();
    Worker& first = *workers_[0];
    for (unsigned w = 0; w < threads_; ++w)
      for (const std::uint64_t packed : workers_[w]->part.hits) {
        const Key k = Key::unpack(packed);
        first.scratch_for(layout::brick_of(k)).hit.set(layout::local_of(k));
      }

    plan_chunks();
    auto job = [&](unsigned w) {
      BrickCursor cursor{{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, workers_[w].get()};
      for (const Ray *pos, *stop; next_rays(pos, stop);)
        for (; pos != stop; ++pos) {
          int step[3];
          WalkState state;
          detail::setup_walk(map_->grid(), origin_, pos->end, origin_key_, pos->key, step, state);
          cursor.start(origin_key_, step, pos->key);
          cursor.visit();  // the origin voxel
          walk_ray(state, cursor);
        }
      workers_[w]->visits = cursor.visits;
    };
    run(job);
    for (unsigned w = 0; w < threads_; ++w) st.ray_keys += workers_[w]->visits;
    apply_hashed(st);
  }

  // walk_ray's cursor for the hashed scratch: per-axis integer keys, with the brick looked up only
  // when a step leaves it (a Key object per voxel went through memory and stalled the CPU).
  struct BrickCursor {
    std::int64_t k[3], dir[3], end[3];
    Worker* worker;
    std::size_t visits = 0;
    VoxelMask* miss = nullptr;  // of k's brick; null after a step into another brick

    void start(const std::int32_t (&from)[3], const int (&step)[3], const std::int32_t (&to)[3]) {
      for (int a = 0; a < 3; ++a) {
        k[a] = from[a];
        dir[a] = step[a];
        end[a] = to[a];
      }
      miss = nullptr;
    }
    template <int Axis>
    void step() {
      const std::int64_t before = k[Axis];
      k[Axis] += dir[Axis];
      if ((k[Axis] ^ before) >> kBrickBits) miss = nullptr;
    }
    bool at_end() const { return k[0] == end[0] && k[1] == end[1] && k[2] == end[2]; }
    bool visit() {
      // OctoMap only asserts here; a walk that would leave the key range ends instead.
      if (((k[0] | k[1] | k[2]) & ~(Key::extent - 1)) != 0) return false;
      if (!miss)
        miss = &worker
                    ->scratch_for(layout::pack_brick(k[0] >> kBrickBits, k[1] >> kBrickBits,
                                                     k[2] >> kBrickBits))
                    .miss;
      constexpr std::int64_t m = kBrickEdge - 1;
      miss->set(static_cast<int>((k[0] & m) | ((k[1] & m) << kBrickBits) |
                                 ((k[2] & m) << (2 * kBrickBits))));
      ++visits;
      return true;
    }
  };

  // The rays of all Parts in chunks: small chunks balance the threads (rays differ in length).
  void plan_chunks() {
    chunk_ = std::max<std::size_t>(256, std::min<std::size_t>(4096, rays_total_ / 64 + 1));
    part_chunks_.resize(threads_ + 1);
    part_chunks_[0] = 0;
    for (unsigned w = 0; w < threads_; ++w)
      part_chunks_[w + 1] = part_chunks_[w] + (workers_[w]->part.rays.size() + chunk_ - 1) / chunk_;
    next_chunk_->store(0, std::memory_order_relaxed);
  }
  // Claims the next chunk of rays; false when every chunk is taken.
  bool next_rays(const Ray*& first, const Ray*& last) {
    const std::size_t c = next_chunk_->fetch_add(1, std::memory_order_relaxed);
    if (c >= part_chunks_[threads_]) return false;
    unsigned w = 0;
    while (c >= part_chunks_[w + 1]) ++w;
    const auto& rays = workers_[w]->part.rays;
    const std::size_t begin = (c - part_chunks_[w]) * chunk_;
    first = rays.data() + begin;
    last = rays.data() + std::min(rays.size(), begin + chunk_);
    return true;
  }

  template <class Job>
  void run(Job& job) {
    if (threads_ == 1) {
      job(0u);
      return;
    }
    if (!pool_) pool_ = std::make_unique<detail::ThreadPool>(threads_);
    pool_->run(job);
  }

  // ---- 3. apply -------------------------------------------------------------------------
  //
  // Gather: the touched bricks with their masks, in groups whose concatenation is z, y, x brick
  // order. Create: the map bricks in that order, serially (the map's storage order never depends
  // on the path or the thread count). Update: every group's bricks, in parallel (each brick is
  // updated by one thread; the map's voxel count is summed afterwards).

  void apply_dense(ScanStats& st) {
    const detail::ScanBitmap& shape = workers_[0]->hit;  // every bitmap has the scan's box
    const std::int64_t nbx = shape.bricks(0), nby = shape.bricks(1), rows = nby * shape.bricks(2);
    const std::int64_t* lo = shape.lo();
    const auto groups = static_cast<std::size_t>(
        std::min<std::int64_t>(rows, threads_ == 1 ? 1 : 8 * std::int64_t{threads_}));
    const auto rows_per_group = (static_cast<std::size_t>(rows) + groups - 1) / groups;
    start_groups(groups);
    // One thread, one group: room for every brick of the box (capped), so a cold process does not
    // grow it through a doubling series of copies and fresh pages (the reserve stays untouched
    // until written). Not with threads: many large reserves made the threads' mapping churn.
    if (groups == 1)
      groups_[0].reserve(
          static_cast<std::size_t>(std::min<std::int64_t>(std::int64_t{1} << 16, rows * nbx)));
    for (unsigned w = 0; w < threads_; ++w) {  // here, not in the job: a thread may get no group
      workers_[w]->row_hit.resize(static_cast<std::size_t>(nbx));
      workers_[w]->row_miss.resize(static_cast<std::size_t>(nbx));
    }
    auto gather = [&](unsigned w) {
      Worker& worker = *workers_[w];
      for (std::size_t g; (g = next_chunk_->fetch_add(1, std::memory_order_relaxed)) < groups;) {
        const auto first = static_cast<std::int64_t>(g * rows_per_group);
        const auto last = std::min(rows, static_cast<std::int64_t>((g + 1) * rows_per_group));
        for (std::int64_t row = first; row < last; ++row) {  // rows differ: no shared words
          const std::int64_t by = row % nby, bz = row / nby;
          for (unsigned t = 0; t < threads_; ++t) {
            workers_[t]->hit.take_brick_row(by, bz, worker.row_hit.data());
            workers_[t]->miss.take_brick_row(by, bz, worker.row_miss.data());
          }
          for (std::int64_t bx = 0; bx < nbx; ++bx) {
            VoxelMask& hit = worker.row_hit[static_cast<std::size_t>(bx)];
            VoxelMask& miss = worker.row_miss[static_cast<std::size_t>(bx)];
            if (!hit.any() && !miss.any()) continue;
            groups_[g].push_back(
                {layout::pack_brick((lo[0] >> kBrickBits) + bx, (lo[1] >> kBrickBits) + by,
                                    (lo[2] >> kBrickBits) + bz),
                 0, hit, miss});
            hit.clear();
            miss.clear();
          }
        }
      }
    };
    run(gather);
    for (unsigned w = 0; w < threads_; ++w) {
      workers_[w]->hit.mark_clean();
      workers_[w]->miss.mark_clean();
    }
    update_groups(st);
  }

  void apply_hashed(ScanStats& st) {
    Worker& first = *workers_[0];
    for (unsigned w = 1; w < threads_; ++w) {  // OR the other threads' masks into the first's
      Worker& other = *workers_[w];
      for (std::size_t j = 0; j < other.used; ++j) {
        Scratch& into = first.scratch_for(other.scratch[j].coord);
        for (std::size_t i = 0; i < into.miss.w.size(); ++i)
          into.miss.w[i] |= other.scratch[j].miss.w[i];
      }
      other.reset_hashed();
    }
    order_.clear();
    for (std::size_t j = 0; j < first.used; ++j) order_.push_back(static_cast<std::uint32_t>(j));
    auto zyx = [&](std::uint32_t j) {
      const auto o = layout::origin_of(first.scratch[j].coord);
      return std::array<std::int64_t, 3>{o[2], o[1], o[0]};
    };
    std::sort(order_.begin(), order_.end(),
              [&](std::uint32_t a, std::uint32_t b) { return zyx(a) < zyx(b); });
    constexpr std::size_t kGroup = 256;
    start_groups((order_.size() + kGroup - 1) / kGroup);
    for (std::size_t k = 0; k < order_.size(); ++k) {
      const Scratch& sc = first.scratch[order_[k]];
      groups_[k / kGroup].push_back({sc.coord, 0, sc.hit, sc.miss});
    }
    first.reset_hashed();
    update_groups(st);
  }

  void start_groups(std::size_t groups) {
    if (groups_.size() < groups) groups_.resize(groups);
    for (std::size_t g = 0; g < groups; ++g) groups_[g].clear();
    group_count_ = groups;
    next_chunk_->store(0, std::memory_order_relaxed);
  }

  // Occupied wins; every touched voxel gets exactly one update.
  void update_groups(ScanStats& st) {
    if (map_->num_bricks() == 0) {  // a fresh map: every touched brick is new
      std::size_t touched = 0;
      for (std::size_t g = 0; g < group_count_; ++g) touched += groups_[g].size();
      map_->reserve_bricks(touched);
    }
    for (std::size_t g = 0; g < group_count_; ++g)
      for (BrickUpdate& u : groups_[g]) {
        u.slot = map_->brick_slot(u.coord);
        map_->prepare_values(map_->brick_at(u.slot));  // the map's pool is serial
        for (std::size_t i = 0; i < u.miss.w.size(); ++i) u.miss.w[i] &= ~u.hit.w[i];
      }
    const float hit_l = hit_l_, miss_l = miss_l_;
    const bool hits_here = !rated_;          // rated hits carry their own sums: apply_rated_hits()
    if (map_->change_detection_enabled()) {  // records per voxel, in one thread
      for (std::size_t g = 0; g < group_count_; ++g)
        for (const BrickUpdate& u : groups_[g]) {
          auto& brick = map_->brick_at(u.slot);
          if (hits_here) map_->update_masked(brick, u.hit, hit_l);
          map_->update_masked(brick, u.miss, miss_l);
          if (hits_here) st.occupied_voxels += static_cast<std::size_t>(u.hit.count());
          st.free_voxels += static_cast<std::size_t>(u.miss.count());
        }
      if (rated_) apply_rated_hits(st);
      return;
    }
    next_chunk_->store(0, std::memory_order_relaxed);
    auto update = [&](unsigned w) {
      Worker& worker = *workers_[w];
      worker.occupied = worker.free = worker.added = 0;
      for (std::size_t g;
           (g = next_chunk_->fetch_add(1, std::memory_order_relaxed)) < group_count_;)
        for (const BrickUpdate& u : groups_[g]) {
          auto& brick = map_->brick_at(u.slot);
          if (hits_here) {
            worker.added += map_->update_brick(brick, u.hit, hit_l);
            worker.occupied += static_cast<std::size_t>(u.hit.count());
          }
          worker.added += map_->update_brick(brick, u.miss, miss_l);
          worker.free += static_cast<std::size_t>(u.miss.count());
        }
    };
    run(update);
    for (unsigned w = 0; w < threads_; ++w) {
      st.occupied_voxels += workers_[w]->occupied;
      st.free_voxels += workers_[w]->free;
      map_->add_known(workers_[w]->added);
    }
    if (rated_) apply_rated_hits(st);
  }

  // Eq 15: every endpoint voxel gets the sum of its endpoints' log-odds, summed in double in
  // point order (Parts hold consecutive points in worker order) and applied in key order, so the
  // map does not depend on the thread count. Their bricks exist already (update_groups).
  void apply_rated_hits(ScanStats& st) {
    sums_.clear();
    for (unsigned w = 0; w < threads_; ++w) {
      const Part& part = workers_[w]->part;
      for (std::size_t j = 0; j < part.hits.size(); ++j)
        sums_.push_back({part.hits[j], sums_.size(), part.hit_logodds[j]});
    }
    std::sort(sums_.begin(), sums_.end(), [](const RatedHit& a, const RatedHit& b) {
      return a.key != b.key ? a.key < b.key : a.order < b.order;
    });
    for (std::size_t j = 0; j < sums_.size();) {
      const std::uint64_t key = sums_[j].key;
      double sum = 0.0;
      for (; j < sums_.size() && sums_[j].key == key; ++j) sum += sums_[j].logodds;
      map_->update(Key::unpack(key), static_cast<float>(sum));
      ++st.occupied_voxels;
    }
  }

  map_type* map_;
  Model model_;
  unsigned threads_ = 0;
  std::size_t scratch_limit_ = std::size_t{384} << 20;
  std::unique_ptr<detail::ThreadPool> pool_;      // created on the first multithreaded scan
  std::vector<std::unique_ptr<Worker>> workers_;  // [0] is the calling thread's
  // Next chunk of work to take (on the heap so that the inserter stays movable).
  std::unique_ptr<std::atomic<std::size_t>> next_chunk_ =
      std::make_unique<std::atomic<std::size_t>>(0);

  // This scan (kept between scans for their memory).
  Point3f origin_;
  std::int32_t origin_key_[3] = {0, 0, 0};
  bool origin_in_range_ = false;
  std::size_t rays_total_ = 0, hits_total_ = 0;  // over all Parts
  std::vector<std::size_t> part_chunks_;         // first chunk of each Part (prefix sums)
  std::size_t chunk_ = 1;                        // rays per chunk
  std::vector<std::uint64_t> endpoints_;         // discretize: distinct endpoint keys
  std::size_t steps_ = 0;                        // sum of |end - origin|_1 over the rays
  std::int64_t key_min_[3] = {0, 0, 0}, key_max_[3] = {0, 0, 0};
  std::int64_t box_lo_[3] = {0, 0, 0}, box_size_[3] = {0, 0, 0};
  bool byte_marks_ = false;  // the dense box marks free voxels in bytes (dense_fits)
  std::vector<std::vector<BrickUpdate>> groups_;  // touched bricks, z, y, x order overall
  std::size_t group_count_ = 0;
  std::vector<std::uint32_t> order_;  // hashed path: scratch slots in z, y, x order
  // The kind of scan being inserted.
  bool rated_ = false;
  float hit_l_ = 0.0f, miss_l_ = 0.0f;
  struct RatedHit {
    std::uint64_t key;
    std::size_t order;
    float logodds;
  };
  std::vector<RatedHit> sums_;  // insert_rated: the scan's endpoints, sorted by key
};

/// One-shot convenience: OctoMap's insertPointCloud with the default model. For many scans keep
/// a ScanInserter, which reuses its scratch memory.
template <class Key, class Points, class Origin>
ScanStats insert_point_cloud(OccupancyMap<Key>& map, const Origin& origin, const Points& points,
                             double max_range = -1.0, bool discretize = false,
                             OctoMapModel model = {}) {
  ScanInserter<Key, OctoMapModel> inserter(map, model);
  return inserter.insert_point_cloud(origin, points, max_range, discretize);
}

}  // namespace knnocc
