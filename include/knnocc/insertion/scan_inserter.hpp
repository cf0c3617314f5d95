// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// ScanInserter: OctoMap's insertPointCloud(points, origin, max_range, discretize) on an
// OccupancyMap, as insert_point_cloud(origin, points, max_range, discretize), with the same map as
// result.
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
// One scan in three phases, each split between the inserter's threads; what a phase hands to the
// next is a value (detail::CollectedScan, detail::DenseBox, detail::BrickGroups), and each pass
// hands out its own work items (detail::WorkQueue):
//   1. collect (detail/collect.hpp): per point the max-range rule, the ray's end point and the hit
//      key; the key box of the scan. Threads take equal shares of the points (when the point
//      container has random access).
//   2. walk: every ray marks its voxels in a per-scan scratch: a dense bit (or byte) per voxel of
//      the box when it is small enough (detail/dense_box.hpp, raycast/detail/scan_bitmap.hpp),
//      walked many rays at once (raycast/detail/fan_walk.hpp), else hashed masks per touched brick
//      (detail/hashed_marks.hpp). Threads take chunks of rays into their own scratch; free and
//      occupied are unions, so the result does not depend on which thread walked which ray.
//      Large scans whose dense box is known in advance run 1 and 2 a chunk of points at a time
//      (insert_chunked): each thread takes chunks in turn, collects them (the hits straight into
//      its hit bitmap) and walks their rays into its own scratch, all in one run of the threads;
//      this bounds the per-point buffers. With one thread, a scan with few points for its box
//      keeps its hits as 4-byte codes instead of a hit bitmap (detail/hit_codes.hpp).
//   3. apply (detail/brick_updates.hpp): the touched bricks with the thread scratches OR-ed,
//      taken in z, y, x brick order whatever the path or thread count (the dense scratch gathered
//      into records, the hashed scratch read in place through a sorted index); the missing map
//      bricks created in that order (one thread), then every touched voxel updated exactly once,
//      occupied first (each brick by one thread); a rated scan's endpoint voxels then get their
//      sums (eq 15, detail/rated_sums.hpp). One thread with no map memory limit takes the dense
//      scratch brick row by brick row and updates each touched brick as it is found, in the same
//      order, without a record per brick (apply_dense_serial): the same map, less memory.
// The scratch is kept between scans, so a warmed-up inserter allocates nothing per scan;
// scratch_usage() tells what it holds, part by part.
//
// ScanInserter is the scan integrator of Mapper (mapper.hpp): `insert_point_cloud` applies a scan
// with the model's fixed hit and miss log-odds, `insert_rated` a scan whose endpoints the sensor
// model rated one by one (EndpointRating: each its own occupied log-odds and its own "casts a free
// ray"); a voxel holding endpoints then receives the sum of their log-odds (eq 15) and no free
// update (occupied wins), free voxels receive the model's miss_logodds() once per scan.
//
// Thread safety: an inserter is one writer (of its map); use one per thread, on different maps.
// With threads > 1 it runs its own workers inside each call and returns when they are done.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <memory>
#include <optional>
#include <type_traits>
#include <utility>
#include <vector>

#include "../core/config.hpp"
#include "../core/point3.hpp"
#include "../core/point_traits.hpp"
#include "../map/detail/brick_access.hpp"
#include "../map/occupancy_map.hpp"
#include "../raycast/dda.hpp"
#include "../raycast/detail/fan_walk.hpp"
#include "../sensor/endpoint_rating.hpp"
#include "../sensor/octomap_model.hpp"
#include "detail/brick_updates.hpp"
#include "detail/clip.hpp"
#include "detail/collect.hpp"
#include "detail/crossing_walk.hpp"
#include "detail/dense_box.hpp"
#include "detail/rated_sums.hpp"
#include "detail/ray_chunks.hpp"
#include "detail/thread_scratch.hpp"
#include "detail/work_queue.hpp"
#include "scan_stats.hpp"

namespace knnocc {

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

  unsigned threads() const { return team_.size(); }
  /// Threads for the following scans (>= 1; 0 is rejected with std::invalid_argument).
  void set_threads(unsigned threads) {
    if (threads < 1) detail::invalid_argument("threads must be >= 1");
    team_.resize(threads);
    while (scratch_.size() < threads) scratch_.push_back(std::make_unique<detail::ThreadScratch>());
  }

  /// Address space the dense per-scan scratch may take, all threads together (default 384 MB,
  /// two bitmaps per thread; pages no ray touches stay unmapped, so resident memory is usually far
  /// less; a box marked in bytes, ScanStats::byte_marks, takes 9 bits per voxel instead of 2 and
  /// falls back to bits when the limit is too small for bytes). A scan whose box needs more uses
  /// the hashed scratch (slower, same map); 0 always does.
  void set_scratch_limit(std::size_t bytes) { scratch_limit_ = bytes; }
  std::size_t scratch_limit() const { return scratch_limit_; }

  /// Bytes of the scratch that grows with the bricks a scan touches (hashed scratch, brick
  /// groups), kept between scans. Under the map's memory limit (OccupancyMap::set_memory_limit)
  /// this scratch and the map share the limit: a scan whose scratch would take the two past it
  /// reports MemoryLimitError before allocating, and the dense scratch takes at most half of
  /// the room the map leaves (scratch_limit() still bounds it).
  std::size_t memory_usage() const { return apply_scratch_bytes(); }

  /// All the scratch kept between scans, by part (what the benches print).
  ScratchUsage scratch_usage() const {
    ScratchUsage u;
    for (unsigned t = 0; t < scratch_.size(); ++t) {
      const detail::ThreadScratch& s = *scratch_[t];
      u.hit_bitmaps += s.hit.capacity_bytes();
      u.miss_bitmaps += s.miss.capacity_bytes();
      u.point_buffers += s.part.rays.capacity_bytes() + s.part.hits.capacity_bytes() +
                         s.part.hit_logodds.capacity() * sizeof(float) +
                         s.hit_list.capacity_bytes() + s.hit_rows.capacity_bytes();
      u.ray_blocks += sizeof(*s.block);
      u.hashed += s.hashed.memory_usage();
      u.other += (s.row_hit.capacity() + s.row_miss.capacity()) * sizeof(VoxelMask) +
                 s.crossing.capacity() * sizeof(detail::RayEnd) + s.hit_codes.memory_usage() +
                 s.row_any.capacity() * sizeof(std::uint64_t);
    }
    u.brick_groups = apply_lists_bytes();
    u.other += first_chunk_.capacity() * sizeof(std::size_t) +
               endpoints_.capacity() * sizeof(std::uint64_t) + sums_.capacity() * sizeof(sums_[0]);
    return u;
  }

  /// Restricts the following scans to the voxels of `bounds` (a tile of a larger map,
  /// tiles/tile_integrator.hpp): every voxel inside gets exactly the update the whole scan gives
  /// it, no voxel outside is touched, and a ray that cannot reach the box is not walked
  /// (detail/clip.hpp). clear_clip() lifts the restriction.
  void set_clip(const KeyBounds<Key>& bounds) {
    detail::KeyBox b;
    for (int a = 0; a < 3; ++a) {
      b.lo[a] = bounds.lo[a];
      b.hi[a] = bounds.hi[a];
    }
    clip_ = b;
  }
  void clear_clip() { clip_.reset(); }
  bool clipped() const { return clip_.has_value(); }

 private:
  // The clip of the apply's brick filter: set when the clip's edges are whole bricks (a scan from
  // inside it then marks voxels outside it, detail/clip.hpp).
  const detail::KeyBox* clip() const {
    return clip_ && detail::brick_aligned(*clip_) ? &*clip_ : nullptr;
  }

 public:
  /// Inserts one scan of world-frame points seen from `origin`. max_range < 0: no limit;
  /// max_range == 0 or NaN is rejected (std::invalid_argument; abort without exceptions).
  template <class Points, class Origin>
  ScanStats insert_point_cloud(const Origin& origin, const Points& points, double max_range = -1.0,
                               bool discretize = false) {
    detail::check_max_range(max_range);
    ScanStats st;
    const Point3f o = detail::to_point3f(origin);
    if (!detail::finite(o)) {
      st.origin_valid = false;
      for (const auto& p : points) (void)p, ++st.points;
      return st;
    }
    const auto scan_origin = detail::ScanOrigin::of(map_->grid(), o);
    const detail::ScanValues values{model_.hit_logodds(), model_.miss_logodds(), false};
    if constexpr (detail::random_access_points<Points>) {
      if (!discretize && !clip_ && insert_chunked(scan_origin, points, max_range, values, st))
        return st;
    }
    const detail::CollectedScan scan = collect(scan_origin, points, max_range, discretize, nullptr);
    add_counts(scan.counts, st);
    walk_and_apply(scan_origin, scan, values, st);
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
    detail::check_max_range(max_range);
    const auto n = static_cast<std::size_t>(std::distance(std::begin(points), std::end(points)));
    if (n != ratings.size())
      detail::invalid_argument("insert_rated: one rating per point expected");
    ScanStats st;
    const Point3f o = detail::to_point3f(origin);
    if (!detail::finite(o)) {
      st.origin_valid = false;
      st.points = n;
      return st;
    }
    const auto scan_origin = detail::ScanOrigin::of(map_->grid(), o);
    const detail::ScanValues values{0.0f, model_.miss_logodds(), true};
    const detail::CollectedScan scan =
        collect(scan_origin, points, max_range, false, ratings.data());
    add_counts(scan.counts, st);
    walk_and_apply(scan_origin, scan, values, st);
    st.chunks = 1;
    return st;
  }

 private:
  using layout = BrickLayout<Key>;
  using RayEnd = detail::RayEnd;

  // Scans of fewer points are collected (and bounded) on one thread: waking the others costs more.
  static constexpr std::size_t kThreadedPoints = 2 * chunk_points;

  static void add_counts(const detail::PointCounts& c, ScanStats& st) {
    st.points += c.points;
    st.nonfinite += c.nonfinite;
    st.out_of_range += c.out_of_range;
    st.beyond_max_range += c.beyond_max_range;
  }
  detail::ThreadScratch& scratch(unsigned t) { return *scratch_[t]; }

  // ---- 1. collect -----------------------------------------------------------------------

  detail::Collector<Key> collector(unsigned t, const detail::ScanOrigin& o,
                                   double max_range) const {
    return detail::Collector<Key>{o, max_range, detail::KeyRounding<Key>(map_->grid()),
                                  scratch_[t]->part};
  }
  void start_parts(const detail::ScanOrigin& o) {
    for (unsigned t = 0; t < threads(); ++t) scratch(t).part.template start<Key>(o);
  }

  // Fills the threads' parts (in parallel when the points allow random access); the scan's rays
  // are the union of all parts' rays.
  template <class Points>
  detail::CollectedScan collect(const detail::ScanOrigin& o, const Points& points, double max_range,
                                bool discretize, const EndpointRating* ratings) {
    start_parts(o);
    if (discretize) {
      detail::collect_discretized(map_->grid(), points, collector(0, o, max_range), endpoints_);
    } else if constexpr (detail::random_access_points<Points>) {
      const auto first = std::begin(points);
      const auto n = static_cast<std::size_t>(std::distance(first, std::end(points)));
      const unsigned parts = n >= kThreadedPoints ? threads() : 1;
      auto job = [&](unsigned t) {
        const std::size_t a = n * t / parts, b = n * (t + 1) / parts;
        collector(t, o, max_range)
            .add_points(first + static_cast<std::ptrdiff_t>(a),
                        first + static_cast<std::ptrdiff_t>(b), ratings ? ratings + a : nullptr);
      };
      team_.run_on(parts, job);
    } else {
      collector(0, o, max_range).add_points(std::begin(points), std::end(points), ratings);
    }
    detail::CollectedScan scan;
    scan.box = detail::KeyBox::empty<Key>();
    for (unsigned t = 0; t < threads(); ++t) {
      detail::ScanPart& part = scratch(t).part;
      std::vector<detail::RayEnd>& crossing = scratch(t).crossing;
      crossing.clear();
      if (clip_) detail::clip_part<Key>(part, o, *clip_, crossing, 1.0 / map_->resolution());
      scan.crossing += crossing.size();
      scan.box.merge(part.box);
      scan.steps += part.steps;
      scan.rays += part.rays.size();
      scan.hits += part.hits.size();
      scan.counts += part.counts;
    }
    return scan;
  }

  // ---- 2. walk, and 3. apply --------------------------------------------------------------

  void walk_and_apply(const detail::ScanOrigin& o, const detail::CollectedScan& scan,
                      const detail::ScanValues& values, ScanStats& st) {
    if (scan.hits == 0 && scan.rays == 0 && scan.crossing == 0) return;
    detail::RayChunks rays(scratch_, threads(), scan.rays, first_chunk_);
    // Under a map memory limit the dense scratch takes at most half of the room the map leaves.
    const std::size_t limit = map_->memory_limit(), in_map = map_->memory_usage();
    const std::size_t dense_limit =
        limit ? std::min(scratch_limit_, limit > in_map ? (limit - in_map) / 2 : 0)
              : scratch_limit_;
    if (const auto box =
            detail::plan_dense_box<Key>(scan.box, scan.steps, dense_limit, threads())) {
      st.byte_marks = box->byte_marks;
      prepare_dense(*box);
      const detail::RayFan fan = dense_fan(o, *box);
      auto job = [&](unsigned t) {
        detail::ThreadScratch& mine = scratch(t);
        mark_hits(mine);
        mine.visits = walk_dense_rays(mine, fan, [&rays](const RayEnd*& pos, const RayEnd*& stop) {
          return rays.take(pos, stop);
        });
        if (!mine.crossing.empty()) mine.visits += walk_crossing_dense(mine, o, fan);
      };
      team_.run(job);
      add_visits(st);
      apply_dense(values, st);
      return;
    }
    // The threads' hashed scratch shares the room the map leaves under its limit.
    const std::size_t elsewhere = in_map + apply_lists_bytes();
    if (limit && elsewhere >= limit) detail::memory_limit_exceeded(limit, elsewhere);
    for (unsigned t = 0; t < threads(); ++t)
      scratch(t).hashed.set_cap(limit ? (limit - elsewhere) / threads() : 0, limit, elsewhere);
    // Under a limit the first thread's scratch, which ends up holding every touched brick, also
    // counts the map bricks they will add: a scan too big for the limit stops sooner.
    const detail::BrickReader<Key> bricks(*map_);
    scratch(0).hashed.count_map_bricks(limit ? &bricks.brick_index() : nullptr,
                                       sizeof(typename map_type::Brick),
                                       bricks.bricks().capacity() - map_->num_bricks());
    walk_hashed(o, rays);
    add_visits(st);
    detail::order_hashed<Key>(scratch_, threads(), order_, slots_, limit, in_map, clip());
    apply(detail::HashedUpdates{scratch(0).hashed, order_, slots_}, values, st);
    scratch(0).hashed.clear();
  }

  // The apply's lists of touched bricks: the dense path's records, the hashed path's order and
  // slots.
  std::size_t apply_lists_bytes() const {
    return bricks_.memory_usage() + (order_.capacity() + slots_.capacity()) * sizeof(std::uint32_t);
  }

  // The inserter's own memory held through the apply (hashed scratch, brick groups, order, slots).
  std::size_t apply_scratch_bytes() const {
    std::size_t bytes = apply_lists_bytes();
    for (unsigned t = 0; t < threads(); ++t) bytes += scratch_[t]->hashed.memory_usage();
    return bytes;
  }

  // Lowers the map's memory limit by the inserter's scratch while the scan is applied (the limit
  // covers both), and restores it.
  class ScratchCounted {
   public:
    ScratchCounted(map_type& map, std::size_t scratch) : map_(map), limit_(map.memory_limit()) {
      if (!limit_) return;
      if (scratch >= limit_) detail::memory_limit_exceeded(limit_, map.memory_usage() + scratch);
      map.set_memory_limit(limit_ - scratch);
    }
    ~ScratchCounted() { map_.set_memory_limit(limit_); }
    ScratchCounted(const ScratchCounted&) = delete;
    ScratchCounted& operator=(const ScratchCounted&) = delete;

   private:
    map_type& map_;
    std::size_t limit_;
  };

  void add_visits(ScanStats& st) {
    for (unsigned t = 0; t < threads(); ++t) st.ray_keys += scratch(t).visits;
  }

  // The dense path's bitmaps of the box, all zero (the hit bitmaps only if `hit_bitmaps`).
  void prepare_dense(const detail::DenseBox& box, bool hit_bitmaps = true) {
    for (unsigned t = 0; t < threads(); ++t) {
      if (hit_bitmaps) scratch(t).hit.reshape(box.lo, box.size);
      scratch(t).miss.reshape(box.lo, box.size, box.byte_marks);
    }
  }
  detail::RayFan dense_fan(const detail::ScanOrigin& o, const detail::DenseBox& box) {
    const detail::ScanBitmap& bitmap = scratch(0).miss;  // every thread's bitmaps alike
    return detail::RayFan(map_->grid(), o.point, o.key, box.lo,
                          {bitmap.stride(0), bitmap.stride(1), bitmap.stride(2)});
  }

  // The thread's part's endpoints into its hit bitmap.
  static void mark_hits(detail::ThreadScratch& mine) {
    for (const std::uint64_t packed : mine.part.hits) {
      const Key k = Key::unpack(packed);
      detail::set_bit(mine.hit.words(), mine.hit.index(k[0], k[1], k[2]));
    }
  }

  // The rays more(pos, stop) hands out into the thread's miss bitmap, on the fastest walk for its
  // marks; returns the voxels visited.
  template <class More>
  std::size_t walk_dense_rays(detail::ThreadScratch& mine, const detail::RayFan& fan, More&& more) {
    if (mine.miss.has_bytes()) {
      const detail::ByteMarks marks{mine.miss.bytes()};
      return detail::walk_fan(detail::best_walk_path<detail::ByteMarks>(), map_->grid(), fan,
                              *mine.block, more, marks);
    }
    const detail::BitMarks marks{mine.miss.words()};
    return detail::walk_fan(detail::best_walk_path<detail::BitMarks>(), map_->grid(), fan,
                            *mine.block, more, marks);
  }

  // A clipped scan's crossing rays into the thread's miss bitmap (detail/crossing_walk.hpp).
  std::size_t walk_crossing_dense(detail::ThreadScratch& mine, const detail::ScanOrigin& o,
                                  const detail::RayFan& fan) {
    return detail::walk_crossing_dense(map_->grid(), mine, o, fan, *clip_, clip() != nullptr);
  }

  // The hashed path: every hit into the first thread's bricks, then each thread's chunks of rays
  // into its own bricks' miss masks, walked one ray at a time.
  void walk_hashed(const detail::ScanOrigin& o, detail::RayChunks& rays) {
    for (unsigned t = 0; t < threads(); ++t) scratch(t).hashed.clear();
    detail::HashedMarks& first = scratch(0).hashed;
    for (unsigned t = 0; t < threads(); ++t)
      for (const std::uint64_t packed : scratch(t).part.hits) {
        const Key k = Key::unpack(packed);
        first.set_hit(layout::brick_of(k), layout::local_of(k));
      }
    auto job = [&](unsigned t) {
      detail::HashedMissMarks<Key> visit{scratch(t).hashed};
      for (const RayEnd *pos, *stop; rays.take(pos, stop);)
        for (; pos != stop; ++pos) {
          int step[3];
          WalkState state;
          detail::setup_walk(map_->grid(), o.point, pos->end, o.key, pos->key, step, state);
          KeyPosition at{{o.key[0], o.key[1], o.key[2]},
                         {step[0], step[1], step[2]},
                         {pos->key[0], pos->key[1], pos->key[2]}};
          visit(at);  // the origin voxel
          walk_ray(state, at, visit);
        }
      if (clip_)
        detail::walk_crossing(map_->grid(), o, scratch(t).crossing, *clip_,
                              [&visit](const KeyPosition& p) { visit(p); });
      scratch(t).visits = visit.visits;
    };
    team_.run(job);
  }

  // The touched bricks (GroupedUpdates or HashedUpdates) into the map, the scratch counted
  // against the map's limit meanwhile.
  template <class Updates>
  void apply(const Updates& bricks, const detail::ScanValues& values, ScanStats& st) {
    const ScratchCounted counted(*map_, apply_scratch_bytes());
    add_updates(detail::apply_updates(*map_, bricks, values, team_, scratch_), values, st);
  }
  // The dense scratch into the map: with one thread and no memory limit brick row by brick row,
  // without the touched bricks' records (the limit refuses a scan's bricks before any is made).
  // codes: the hits are in scratch(0).hit_list (one thread, no limit only).
  void apply_dense(const detail::ScanValues& values, ScanStats& st, bool codes = false) {
    if (threads() == 1 && !map_->memory_limit()) {
      add_updates(detail::apply_dense_serial(*map_, scratch(0), values, codes, clip()), values, st);
      return;
    }
    detail::gather_dense<Key>(team_, scratch_, bricks_, clip());
    apply(detail::GroupedUpdates{bricks_}, values, st);
  }
  void add_updates(const detail::UpdateCounts& c, const detail::ScanValues& values, ScanStats& st) {
    st.occupied_voxels += c.occupied;
    st.free_voxels += c.free;
    if (values.rated)
      st.occupied_voxels += detail::apply_rated_hits(*map_, scratch_, threads(), sums_);
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

  template <class Points>
  bool insert_chunked(const detail::ScanOrigin& o, const Points& points, double max_range,
                      const detail::ScanValues& values, ScanStats& st) {
    const auto first = std::begin(points);
    const auto n = static_cast<std::size_t>(std::distance(first, std::end(points)));
    if (n <= chunk_points || !o.in_range) return false;
    const std::optional<detail::DenseBox> box = chunked_box(o, first, n, max_range);
    if (!box) return false;

    st.byte_marks = box->byte_marks;
    start_parts(o);
    // One thread, no memory limit: a scan with few points for its box keeps its hits as codes (4
    // bytes a hit, detail/hit_codes.hpp) rather than in a hit bitmap (a bit per voxel of the box).
    const auto voxels = static_cast<std::size_t>(box->size[0] * box->size[1] * box->size[2]);
    const bool codes = threads() == 1 && !map_->memory_limit() && n * 64 <= voxels &&
                       scratch(0).hit_codes.shape(box->lo, box->size);
    if (codes) {  // room for every point's hit at once: no copies as the chunks come in
      scratch(0).hit_list.clear();
      scratch(0).hit_list.reserve(n);
    }
    prepare_dense(*box, !codes);
    const detail::RayFan fan = dense_fan(o, *box);
    for (unsigned t = 0; t < threads(); ++t)  // here: a thread may get no chunk of this scan
      scratch(t).part.rays.reserve(chunk_points);
    detail::WorkQueue chunks((n + chunk_points - 1) / chunk_points);
    auto job = [&](unsigned t) {
      detail::ThreadScratch& mine = scratch(t);
      detail::ScanPart& part = mine.part;
      mine.visits = 0;
      for (std::size_t c; chunks.take(c);) {
        const std::size_t a = c * chunk_points, b = std::min(n, a + chunk_points);
        part.rays.clear();
        detail::Collector<Key> collect_chunk = collector(t, o, max_range);
        collect_chunk.hit_map = &mine.hit;
        if (codes) {
          collect_chunk.hit_codes = &mine.hit_codes;
          collect_chunk.hit_list = &mine.hit_list;
        }
        collect_chunk.add_chunk(first + static_cast<std::ptrdiff_t>(a),
                                first + static_cast<std::ptrdiff_t>(b));
        bool given = false;  // the chunk's rays, handed out once
        mine.visits += walk_dense_rays(mine, fan, [&](const RayEnd*& pos, const RayEnd*& stop) {
          pos = part.rays.data();
          stop = given ? pos : pos + part.rays.size();
          given = true;
          return pos != stop;
        });
      }
    };
    team_.run(job);
    for (unsigned t = 0; t < threads(); ++t) add_counts(scratch(t).part.counts, st);
    add_visits(st);
    st.chunks = chunks.size();
    apply_dense(values, st, codes);
    return true;
  }

  // The dense box of a large scan from its points' bounds (and a sample of the rays' lengths in
  // voxels, which only picks the faster path), each thread over its share of the points; nullopt
  // when the points leave the key range (the one-piece path counts them) or the box does not fit.
  template <class It>
  std::optional<detail::DenseBox> chunked_box(const detail::ScanOrigin& o, It first, std::size_t n,
                                              double max_range) {
    const unsigned parts = n >= kThreadedPoints ? threads() : 1;
    auto bound = [&](unsigned t) {
      scratch(t).bounds = detail::point_bounds(first, n * t / parts, n * (t + 1) / parts, o.point,
                                               map_->resolution(), max_range);
    };
    team_.run_on(parts, bound);
    float lo[3] = {o.point.x, o.point.y, o.point.z}, hi[3] = {o.point.x, o.point.y, o.point.z};
    std::uint64_t sampled = 0;
    for (unsigned t = 0; t < parts; ++t) {
      const detail::PointBounds& b = scratch(t).bounds;
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], b.lo[a]);
        hi[a] = std::max(hi[a], b.hi[a]);
      }
      sampled += b.sampled;
    }
    if (max_range > 0) {  // rays end within max_range of the origin (truncated past it)
      const float c[3] = {o.point.x, o.point.y, o.point.z};
      const auto r = detail::to_float(max_range);
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::max(lo[a], c[a] - r);
        hi[a] = std::min(hi[a], c[a] + r);
      }
    }
    Key klo, khi;
    if (!map_->grid().point_to_key(Point3f{lo[0], lo[1], lo[2]}, klo) ||
        !map_->grid().point_to_key(Point3f{hi[0], hi[1], hi[2]}, khi))
      return std::nullopt;
    detail::KeyBox keys;
    for (int a = 0; a < 3; ++a) {
      keys.lo[a] = std::int64_t{klo[a]} - 1;
      keys.hi[a] = std::int64_t{khi[a]} + 1;
    }
    return detail::plan_dense_box<Key>(
        keys, static_cast<std::size_t>(sampled * detail::PointBounds::kSample), scratch_limit_,
        threads());
  }

  map_type* map_;
  Model model_;
  std::optional<detail::KeyBox> clip_;  // set_clip
  std::size_t scratch_limit_ = std::size_t{384} << 20;
  detail::Team team_;
  detail::ThreadScratches scratch_;  // one per thread, [0] the calling thread's
  // Buffers of the phases, kept between scans for their memory.
  std::vector<std::size_t> first_chunk_;  // walk: RayChunks' prefix sums
  std::vector<std::uint64_t> endpoints_;  // collect, discretize: distinct endpoint keys
  detail::BrickGroups bricks_;            // apply: touched bricks, z, y, x order overall
  std::vector<std::uint32_t> order_;      // apply, hashed path: bricks in z, y, x order
  std::vector<std::uint32_t> slots_;      // apply, hashed path: their map slots
  std::vector<detail::RatedHit> sums_;    // apply, rated scans: the endpoints sorted by key
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
