// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// LiveMapper: an occupancy map that follows a SLAM system's corrections exactly (the paper's
// future work, section 5: update the map when loop closure re-poses the keyframes).
//
// It owns the keyframes (id, pose, sensor-frame points, optional map-point ids) and takes
//   add(id, pose, points, ids)  a new keyframe, appended to the insertion order;
//   repose({id -> pose})        any set of keyframes at once (local bundle adjustment, loop
//                               closure); poses equal to the stored ones are no change;
//   remove({ids})               keyframe culling.
// Invariant, after every operation: map() (every voxel's log-odds bit for bit, and which voxels
// are known) and, for the k-NN model, tracker() (s_p of every map point, N, mu, sigma) equal what
// Mapper builds from scratch over the current keyframes in insertion order, each moved into the
// world with its current pose by pose_traits<Pose>::to_world.
//
// A map point's world position (k-NN model, with ids): the position it has in the earliest
// current keyframe (insertion order) that holds it, with that keyframe's current pose. That is
// what a from-scratch Mapper does (KeyframeUnion: an id joins once, at its first position), so
// re-posing or removing that keyframe moves the point to the next holder's view of it.
//
// Cost (see docs/live_mapping.md):
//   add       one keyframe's insertion, as Mapper (both models).
//   OctoMap model, repose/remove: OctoMap's log-odds update with clamping is a fold over the
//             scans that touch a voxel, in order, so a voxel's value depends only on those scans.
//             The region is the union of the brick boxes the changed keyframes reach (old and new
//             poses); every keyframe whose box meets it is replayed, in insertion order, into a
//             scratch map, and the region's bricks are copied back. Keyframes elsewhere are not
//             touched: the cost follows the keyframes that see the changed region, not the map
//             size. When every keyframe is a candidate the map is rebuilt instead (same result).
//   k-NN model, repose/remove: mu and sigma after the first changed keyframe differ, so every
//             later keyframe's ratings change, and the tracker's Welford sums cannot be rewound
//             bit for bit; the map and tracker are rebuilt from scratch (the cost of a rebuild).
//
// Models: OctoMapModel, KnnModel, or one of the same kinds (sensor/sensor_model.hpp); a
// cloud-rated or contextual model is refused at compile time.
//
// A LiveMapper is movable; a moved-from one may only be destroyed or assigned to.
//
// Thread safety: one writer; const queries are safe from many threads while no operation runs.

#include <algorithm>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

#include "../core/config.hpp"
#include "../core/point3.hpp"
#include "../knn/change_set.hpp"
#include "../map/brick.hpp"
#include "../map/detail/brick_access.hpp"
#include "../mapper.hpp"
#include "keyframe_store.hpp"
#include "rigid_pose.hpp"

namespace knnocc {

/// What the last add / repose / remove did.
struct LiveUpdate {
  std::size_t changed = 0;   ///< keyframes added, re-posed (to a different pose) or removed
  std::size_t replayed = 0;  ///< keyframes whose rays were cast again
  std::size_t bricks = 0;    ///< map bricks recomputed by a regional replay
  bool rebuilt = false;      ///< the map (and tracker) were built again from scratch
};

template <class Model = OctoMapModel, class Key = OcKey, class Pose = RigidPose>
class LiveMapper {
  static_assert(detail::has_pose_traits<Pose>::value,
                "LiveMapper's Pose needs pose_traits<Pose> with static Point3d origin(const "
                "Pose&) and static Point3d to_world(const Pose&, const Point3f&) "
                "(live/rigid_pose.hpp)");

  static_assert(!Mapper<Model, Key>::rates_cloud && !Mapper<Model, Key>::contextual,
                "LiveMapper takes a fixed model (OctoMapModel) or one rated per endpoint "
                "(KnnModel): a cloud-rated model (Knn2022Model) or a contextual one (RobustModel) "
                "has no exact replay here; map with Mapper");

 public:
  using mapper_type = Mapper<Model, Key>;
  using map_type = typename mapper_type::map_type;
  using pose_type = Pose;
  using keyframe_type = LiveKeyframe<Pose>;
  static constexpr bool uses_map_cloud = mapper_type::uses_map_cloud;

  /// Options as Mapper's (max_range, discretize, threads, clamping).
  explicit LiveMapper(double resolution, Model model = Model(), MapperOptions options = {})
      : resolution_(resolution),
        model_(std::move(model)),
        options_(options),
        mapper_(resolution_, model_, options_) {}

  const map_type& map() const { return mapper_.map(); }
  const MapperOptions& options() const { return options_; }
  template <bool B = uses_map_cloud, std::enable_if_t<B, int> = 0>
  const typename mapper_type::tracker_type& tracker() const {
    return mapper_.tracker();
  }
  const KeyframeStore<Pose>& keyframes() const { return store_; }
  std::size_t size() const { return store_.size(); }
  bool contains(std::uint64_t id) const { return store_.contains(id); }
  const Pose& pose(std::uint64_t id) const { return store_[store_.position(id)].pose; }
  const LiveUpdate& last_update() const { return last_; }
  /// Bytes held by the stored keyframes (the map's own memory: map().memory_usage()).
  std::size_t keyframe_memory() const { return store_.memory_usage(); }

  /// The points of the current keyframes at their current poses as a from-scratch Mapper counts
  /// them (ScanStats points, nonfinite, out_of_range, beyond_max_range, summed): e.g. the points a
  /// correction moved outside the key range, which the map holds no update from.
  ScanStats point_counts() const {
    ScanStats s;
    for (const keyframe_type& kf : store_.frames()) {
      const Point3f o = detail::to_point3f(pose_traits<Pose>::origin(kf.pose));
      for (const Point3f& p : kf.points) {
        ++s.points;
        const Point3f q = detail::to_point3f(pose_traits<Pose>::to_world(kf.pose, p));
        switch (detail::endpoint_fate(mapper_.map().grid(), q, o, options_.max_range)) {
          case detail::EndpointFate::nonfinite:
            ++s.nonfinite;
            break;
          case detail::EndpointFate::beyond_max_range:
            ++s.beyond_max_range;
            break;
          case detail::EndpointFate::out_of_range:
            ++s.out_of_range;
            break;
          case detail::EndpointFate::inserted:
            break;
        }
      }
    }
    return s;
  }

  /// Bounds the memory of the map (OccupancyMap::set_memory_limit; 0: no bound), now and of every
  /// map built later: rebuilds and the scratch maps of regional replays. An operation that would
  /// pass it throws MemoryLimitError; the keyframes then hold the operation's result but the map
  /// may not: raise the limit and rebuild().
  void set_memory_limit(std::size_t bytes) {
    memory_limit_ = bytes;
    mapper_.map().set_memory_limit(bytes);
  }
  std::size_t memory_limit() const { return memory_limit_; }

  /// Adds keyframe `id` (new id) seen from `pose`; `points` in the sensor frame; `ids` one
  /// map-point id per point or empty (k-NN model: a sequence gives ids always or never; the
  /// OctoMap model ignores them). std::invalid_argument, with nothing changed, on a known id, a
  /// non-finite pose origin, an id count that does not match, id 2^64-1, an id repeated within
  /// the keyframe, or ids mixed.
  void add(std::uint64_t id, const Pose& pose, std::vector<Point3f> points,
           std::vector<std::uint64_t> ids = {}) {
    if (store_.contains(id)) detail::invalid_argument("LiveMapper::add: keyframe id already added");
    check_pose(pose);
    if constexpr (uses_map_cloud) {
      if (!ids.empty() && ids.size() != points.size())
        detail::invalid_argument("LiveMapper::add: one map-point id per point expected");
      for (const std::uint64_t m : ids)
        if (m == KeyframeUnion::kNoId)
          detail::invalid_argument("LiveMapper::add: id 2^64-1 is reserved");
      std::vector<std::uint64_t> scratch;
      detail::check_distinct_ids("LiveMapper::add", ids, scratch);
      if (!points.empty() && ((ids.empty() && with_ids_ > 0) || (!ids.empty() && without_ids_ > 0)))
        detail::invalid_argument("LiveMapper::add: keyframes with and without ids are mixed");
      if (!points.empty()) ++(ids.empty() ? without_ids_ : with_ids_);
    } else {
      ids.clear();  // the OctoMap model needs no map points
    }
    keyframe_type kf;
    kf.id = id;
    kf.pose = pose;
    kf.points = std::move(points);
    kf.ids = std::move(ids);
    const WorldKeyframe w = to_world(kf);
    kf.reach = reach(w);
    insert(mapper_, kf, w);
    store_.push_back(std::move(kf));
    last_ = LiveUpdate{1, 1, 0, false};
  }

  /// Re-poses the keyframes named (id -> new pose); unknown ids or non-finite poses:
  /// std::invalid_argument with nothing changed.
  void repose(const std::vector<std::pair<std::uint64_t, Pose>>& poses) {
    for (const auto& [id, pose] : poses) {
      if (!store_.contains(id)) detail::invalid_argument("LiveMapper::repose: unknown keyframe id");
      check_pose(pose);
    }
    last_ = LiveUpdate{};
    std::vector<BrickBox> region;
    std::vector<std::size_t> moved;
    std::vector<char> seen(store_.size(), 0);
    for (const auto& [id, pose] : poses) {
      const std::size_t i = store_.position(id);
      keyframe_type& kf = store_[i];
      if (kf.pose == pose) continue;
      if (!seen[i]) {
        seen[i] = 1;
        moved.push_back(i);
        region.push_back(kf.reach);  // where it was
      }
      kf.pose = pose;
    }
    last_.changed = moved.size();
    if (moved.empty()) return;
    // The k-NN model rebuilds; so does a re-pose of every keyframe (a loop closure): no boxes.
    if (uses_map_cloud || moved.size() == store_.size()) {
      rebuild();
      return;
    }
    for (const std::size_t i : moved) {  // where it is now
      store_[i].reach = reach(to_world(store_[i]));
      region.push_back(store_[i].reach);
    }
    replay(region);
  }

  /// Removes the keyframes named; unknown ids: std::invalid_argument with nothing changed.
  void remove(const std::vector<std::uint64_t>& ids) {
    for (const std::uint64_t id : ids)
      if (!store_.contains(id)) detail::invalid_argument("LiveMapper::remove: unknown keyframe id");
    last_ = LiveUpdate{};
    std::vector<char> doomed(store_.size(), 0);
    std::vector<BrickBox> region;
    for (const std::uint64_t id : ids) {
      const std::size_t i = store_.position(id);
      if (doomed[i]) continue;
      doomed[i] = 1;
      ++last_.changed;
      region.push_back(store_[i].reach);
      if (!store_[i].points.empty()) --(store_[i].ids.empty() ? without_ids_ : with_ids_);
    }
    store_.erase(doomed);
    if (last_.changed) update(region);
  }

  /// Builds the map (and tracker) again from scratch over the current keyframes.
  void rebuild() {
    mapper_type fresh(resolution_, model_, options_);
    fresh.map().set_memory_limit(memory_limit_);
    for (std::size_t i = 0; i < store_.size(); ++i) {
      const WorldKeyframe w = to_world(store_[i]);
      if constexpr (!uses_map_cloud) store_[i].reach = reach(w);
      insert(fresh, store_[i], w);
    }
    mapper_ = std::move(fresh);
    last_.replayed = store_.size();
    last_.rebuilt = true;
  }

 private:
  using layout = BrickLayout<Key>;

  static void check_pose(const Pose& pose) {
    const Point3d o = pose_traits<Pose>::origin(pose);
    if (!is_finite(o)) detail::invalid_argument("LiveMapper: the pose's origin is not finite");
  }

  // A keyframe as a from-scratch Mapper receives it: sensor origin and world-frame points.
  struct WorldKeyframe {
    Point3d origin;
    std::vector<Point3d> points;
  };
  static WorldKeyframe to_world(const keyframe_type& kf) {
    WorldKeyframe w{pose_traits<Pose>::origin(kf.pose), std::vector<Point3d>(kf.points.size())};
    for (std::size_t j = 0; j < kf.points.size(); ++j)
      w.points[j] = pose_traits<Pose>::to_world(kf.pose, kf.points[j]);
    return w;
  }
  BrickBox reach(const WorldKeyframe& w) const {
    return reach_of<Key>(w.origin, w.points, resolution_, options_.max_range);
  }
  // `w`: to_world(kf), or part of its points (a regional replay).
  static void insert(mapper_type& m, const keyframe_type& kf, const WorldKeyframe& w) {
    if constexpr (uses_map_cloud)
      m.insert_keyframe(w.origin, w.points, kf.ids);
    else
      m.insert_keyframe(w.origin, w.points);
  }

  void update(const std::vector<BrickBox>& region) {
    if constexpr (uses_map_cloud) {
      (void)region;
      rebuild();
    } else {
      replay(region);
    }
  }

  // OctoMap model: the keyframes that reach the region, replayed in order into a scratch map,
  // and the region's bricks copied back.
  void replay(const std::vector<BrickBox>& region) {
    std::vector<std::size_t> candidates;
    for (std::size_t i = 0; i < store_.size(); ++i)
      for (const BrickBox& b : region)
        if (store_[i].reach.intersects(b)) {
          candidates.push_back(i);
          break;
        }
    if (candidates.size() == store_.size()) {
      rebuild();
      return;
    }
    BrickBox all = region.front();  // the region's bounding box, a quick first test
    for (const BrickBox& r : region)
      for (int a = 0; a < 3; ++a) {
        all.lo[a] = std::min(all.lo[a], r.lo[a]);
        all.hi[a] = std::max(all.hi[a], r.hi[a]);
      }
    mapper_type scratch(resolution_, model_, options_);
    scratch.map().set_memory_limit(memory_limit_);
    for (const std::size_t i : candidates) {
      WorldKeyframe w = to_world(store_[i]);
      // Only rays that can reach the region: the others change none of its voxels (one update
      // per voxel per scan, decided by the rays and end points in that voxel alone).
      const RayReach ray(w.origin, options_.max_range);
      std::size_t kept = 0;
      for (const Point3d& p : w.points) {
        double lo[3], hi[3];
        if (!ray.extent(p, lo, hi)) continue;
        const BrickBox b = detail::brick_box<Key>(lo, hi, resolution_);
        if (!b.intersects(all)) continue;
        for (const BrickBox& r : region)
          if (b.intersects(r)) {
            w.points[kept++] = p;
            break;
          }
      }
      w.points.resize(kept);
      insert(scratch, store_[i], w);
    }
    last_.replayed = candidates.size();
    const map_type& from = scratch.map();
    map_type& to = mapper_.map();
    auto in_region = [&](std::uint64_t coord) {
      const auto o = layout::origin_of(coord);
      const std::array<std::int64_t, 3> b{o[0] >> kBrickBits, o[1] >> kBrickBits,
                                          o[2] >> kBrickBits};
      for (const BrickBox& r : region)
        if (r.contains(b)) return true;
      return false;
    };
    // Bricks the replay produced, then bricks of the map the replay has none of (only changed
    // keyframes reached them before: they become unknown).
    detail::BrickWriter<Key> writer(to);
    const detail::BrickReader<Key> old(to), replayed(from);
    for (const auto& b : replayed.bricks())
      if (in_region(b.coord)) {
        writer.copy_brick_from(from, b.coord);
        ++last_.bricks;
      }
    auto clear_if_stale = [&](std::uint64_t coord) {
      if (replayed.find_brick(coord) || !in_region(coord)) return;
      writer.copy_brick_from(from, coord);
      ++last_.bricks;
    };
    for (const BrickBox& r : region) {
      if (r.volume() < static_cast<double>(to.num_bricks())) {
        for (std::int64_t x = r.lo[0]; x <= r.hi[0]; ++x)
          for (std::int64_t y = r.lo[1]; y <= r.hi[1]; ++y)
            for (std::int64_t z = r.lo[2]; z <= r.hi[2]; ++z) {
              const std::uint64_t c = layout::pack_brick(x, y, z);
              const auto* b = old.find_brick(c);
              if (b && b->known.any()) clear_if_stale(c);
            }
      } else {
        for (std::size_t s = 0; s < old.bricks().size(); ++s) {
          const auto& b = old.bricks()[s];
          if (b.known.any()) clear_if_stale(b.coord);
        }
      }
    }
  }

  double resolution_;
  Model model_;
  MapperOptions options_;
  mapper_type mapper_;
  std::size_t memory_limit_ = 0;  // 0: none
  KeyframeStore<Pose> store_;
  std::size_t with_ids_ = 0, without_ids_ = 0;  // keyframes with points, by kind (k-NN model)
  LiveUpdate last_;
};

}  // namespace knnocc
